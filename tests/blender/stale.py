"""Inside `blender -b --factory-startup`: binds are never stale. The Deformer is kept across frames;
an in-place edit of the model's rest vertices or of the cage's rest nodes (same counts) rebuilds it,
and so does a file whose rest content changed while the add-on was off (hash stored at bind, checked
at load, noted for the panel): each time Blender's model equals `mbi deform` on the current rest. The
discontinuity table at a posed frame ranks modified-BI below BI.

    blender -b --factory-startup --python stale.py -- <work dir> <mbi executable>
"""
import os
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import (  # noqa: E402
    agrees_with_mbi_deform, bound_sphere, check, pose_key, positions, run_main,
    select_only)


def setup():
    model, cage = bound_sphere(4)
    U = positions(cage.data)
    pose = pose_key(cage, U + 0.3 * np.stack([U[:, 2] ** 2, np.sin(U[:, 0]), U[:, 0] * U[:, 1]], axis=1))
    pose.value = 1.0
    bpy.context.view_layer.update()
    return model, cage


def set_rest(obj, R):
    """New rest positions of the same count: the mesh's vertices and its basis key."""
    flat = R.astype(np.float32).ravel()
    obj.data.vertices.foreach_set("co", flat)
    if obj.data.shape_keys is not None:
        obj.data.shape_keys.key_blocks["Basis"].data.foreach_set("co", flat)
    obj.data.update()
    bpy.context.view_layer.update()



def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import binding, table_op
    mbi = __import__("mbi_blender.module", fromlist=["load"]).load()
    model, cage = setup()
    agrees_with_mbi_deform(mbi, exe, work, model, cage, "bound")
    kept = binding._bound[model.name_full]
    for frame in (2, 3):
        bpy.context.scene.frame_set(frame)
    check(binding._bound[model.name_full] is kept, "frame changes keep the Deformer (no rebuild)")

    set_rest(model, positions(model.data) * 0.9)
    check(binding._bound[model.name_full] is not kept, "an in-place edit of the model's rest rebuilt the Deformer")
    agrees_with_mbi_deform(mbi, exe, work, model, cage, "model-edited")
    U = positions(cage.data)
    inner = np.argmin(np.linalg.norm(U - U.mean(axis=0), axis=1))
    U[inner] += 0.05
    kept = binding._bound[model.name_full]
    set_rest(cage, U)
    check(binding._bound[model.name_full] is not kept, "an in-place edit of the cage's rest rebuilt the Deformer")
    agrees_with_mbi_deform(mbi, exe, work, model, cage, "cage-edited")

    path, cage_name = os.path.join(work, "stale.blend"), cage.name
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    model, cage = bpy.data.objects["model"], bpy.data.objects[cage_name]
    check(model.name not in binding.notes, "a reopened file with the same rest content: no note")
    addon_utils.disable("mbi_blender")
    set_rest(model, positions(model.data) * 0.95)
    bpy.ops.wm.save_as_mainfile(filepath=path)
    addon_utils.enable("mbi_blender", default_set=True)
    bpy.ops.wm.open_mainfile(filepath=path)
    model, cage = bpy.data.objects["model"], bpy.data.objects[cage_name]
    note = binding.notes.get(model.name, "")
    check("rest shape changed" in note, "a file edited without the add-on is detected at load: %s" % note)
    agrees_with_mbi_deform(mbi, exe, work, model, cage, "reopened")

    select_only([model], model)
    check(bpy.ops.mbi.discontinuity() == {"FINISHED"}, "the discontinuity operator ran")
    frame, rows, faces, seconds = table_op.tables[model.name]
    means = {label: mean for label, mean, _, _ in rows}
    check(faces > 0 and means["mod-BI"] < means["BI"] and means["BI/mod-BI"] > 1,
          "the table over %d faces: BI %.3g, modified-BI %.3g, Phong %.3g (%.3f s)"
          % (faces, means["BI"], means["mod-BI"], means["Phong"], seconds))
    check(model.mbi.bind_seconds > 0, "the bind time is kept for the panel (%.3f s)" % model.mbi.bind_seconds)
    print("PASS")


if __name__ == "__main__":
    run_main(main)
