"""Bake: the bound meshes' positions over a frame range into PC2 files, played back by Blender's own
Mesh Cache modifier, so playback and rendering need neither the add-on nor mbi; un-bake.

The Mesh Cache modifier reads in FRAME mode, which ignores the PC2's start frame and sample rate
(sample k plays at frame k + the modifier's frame_start): the modifier's frame_start is set to the
first baked frame, one sample a scene frame, whatever the scene's frame rate.
"""
import os

import bpy

from . import gn, jobs, live, pc2

MODIFIER = live.CACHE_MODIFIER


def cache_folder(directory):
    if directory.startswith("//") and not bpy.data.filepath:
        raise ValueError("the cache folder %s is relative to the .blend: save the .blend first, or give an "
                         "absolute folder" % directory)
    folder = bpy.path.abspath(directory)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as error:
        raise ValueError("cannot make the cache folder %s: %s" % (folder, error)) from error
    return folder


def bake_job(scene, models, start, end, directory):
    """Checks the request, then returns the job (a generator of progress) that bakes frames start..end."""
    if not models:
        raise ValueError("select meshes bound to an mbi cage")
    if end < start:
        raise ValueError("the frame range %d..%d is empty" % (start, end))
    folder = cache_folder(directory)
    return bake_steps(scene, models, start, end, [cache_path(folder, m) for m in models])


def bake_steps(scene, models, start, end, paths):
    samples = end - start + 1
    writers, committed, frame_before = [], False, scene.frame_current
    try:
        for model, path in zip(models, paths):
            writers.append(pc2.Writer(path, len(model.data.vertices), samples, float(start)))
        for i, frame in enumerate(range(start, end + 1)):
            scene.frame_set(frame)  # the live path writes the models' attributes
            for model, writer in zip(models, writers):
                if model.name in live.errors:
                    raise ValueError("frame %d: %s: %s" % (frame, model.name, live.errors[model.name]))
                writer.write(live.live_positions(model))
            yield (i + 1) / samples
        for writer in writers:
            writer.commit()
        committed = True
        for model, path in zip(models, paths):
            attach(model, bpy.path.relpath(path) if bpy.data.filepath else path, start)
    finally:
        if not committed:
            for writer in writers:
                writer.discard()
        scene.frame_set(frame_before)


def attach(model, filepath, start):
    """The cache played first in the model's stack; its live modifier off."""
    attach_cache(model, filepath, start)
    gn.show(model, False)
    model.mbi.baked = True


def attach_cache(model, filepath, start):
    """The Mesh Cache modifier first in the stack, playing the PC2 file from frame start."""
    modifier = model.modifiers.get(MODIFIER) or model.modifiers.new(MODIFIER, "MESH_CACHE")
    modifier.cache_format = "PC2"
    modifier.filepath = filepath
    modifier.time_mode = "FRAME"
    modifier.play_mode = "SCENE"
    modifier.frame_start = start
    modifier.frame_scale = 1.0
    modifier.interpolation = "LINEAR"
    modifier.deform_mode = "OVERWRITE"
    modifier.forward_axis, modifier.up_axis = "POS_Y", "POS_Z"  # no axis conversion
    if model.modifiers[0] != modifier:
        with bpy.context.temp_override(object=model):
            bpy.ops.object.modifier_move_to_index(modifier=MODIFIER, index=0)


def unbake(model, depsgraph):
    """Back to the live path (a cage: to its own animation): the modifier removed (the file stays)."""
    modifier = model.modifiers.get(MODIFIER)
    if modifier is not None:
        model.modifiers.remove(modifier)
    if model.mbi.is_cage:
        live.update_all(depsgraph)
        return
    model.mbi.baked = False
    gn.show(model, True)
    live.update_all(depsgraph)


def _bound_selection(context):
    return [o for o in context.selected_objects if o.type == "MESH" and o.mbi.cage is not None]


def cache_path(folder, obj):
    return os.path.join(folder, bpy.path.clean_name(obj.name) + ".pc2")


class MBI_OT_bake(jobs.ModalJob, bpy.types.Operator):
    """Bake the selected bound meshes to PC2 point caches played by Mesh Cache modifiers (Esc cancels)"""
    bl_idname = "mbi.bake"
    bl_label = "Bake mbi to point caches"
    bl_options = {"REGISTER", "UNDO"}

    directory: bpy.props.StringProperty(name="Folder", default="//mbi_cache", subtype="DIR_PATH")
    frame_start: bpy.props.IntProperty(name="Start", default=-1, description="First frame (-1: the scene's)")
    frame_end: bpy.props.IntProperty(name="End", default=-1, description="Last frame (-1: the scene's)")

    def make_job(self, context):
        scene = context.scene
        start = scene.frame_start if self.frame_start < 0 else self.frame_start
        end = scene.frame_end if self.frame_end < 0 else self.frame_end
        models = [m for m in _bound_selection(context) if not m.mbi.baked]
        return bake_job(scene, models, start, end, self.directory)


class MBI_OT_unbake(bpy.types.Operator):
    """Remove the selected meshes' point caches and follow the cage live again (a cage: its simulation)"""
    bl_idname = "mbi.unbake"
    bl_label = "Un-bake mbi"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        for model in context.selected_objects:
            if model.mbi.baked or (model.mbi.is_cage and MODIFIER in model.modifiers):
                unbake(model, context.evaluated_depsgraph_get())
        return {"FINISHED"}


_classes = (MBI_OT_bake, MBI_OT_unbake)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
