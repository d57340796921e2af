"""Physics: mbi's co-rotational FEM (mbi.Simulator) moves the cage over a frame range; the cage's
motion is baked to a PC2 played by a Mesh Cache modifier on the cage, then the bound meshes are
baked from it as by the bake operator.

The simulation runs in world space (a Blender unit is a metre), one step of 1/fps s a frame, the
scene's gravity; the first frame of the range is the rest state. Nodes of the cage's pinned
vertex group (weight > 0) are held where they are, or moved by a scripted rigid motion (velocity
and a rotation about an axis, from a start to a stop time: mbi's kinematic constraint).
"""
import os

import bpy
import numpy as np

from . import bake, jobs, live, module, pc2, storage


def pinned_nodes(cage):
    name = cage.mbi.pin_group
    if not name:
        return np.zeros(0, dtype=np.int64)
    group = cage.vertex_groups.get(name)
    if group is None:
        raise ValueError("the cage %s has no vertex group %s (its pinned group)" % (cage.name, name))
    index = group.index
    return np.array([v.index for v in cage.data.vertices
                     if any(g.group == index and g.weight > 0 for g in v.groups)], dtype=np.int64)


def simulator(scene, cage):
    """mbi.Simulator of the cage's rest nodes in world space with the cage's settings and the scene's gravity."""
    mbi = module.load()
    s = cage.mbi
    M = np.array(cage.matrix_world)
    U = storage.positions(cage.data).astype(np.float64) @ M[:3, :3].T + M[:3, 3]
    gravity = tuple(scene.gravity) if scene.use_gravity else (0.0, 0.0, 0.0)
    sim = mbi.Simulator(U, storage.tets(cage.data), youngs_modulus=s.young, poisson_ratio=s.poisson,
                        density=s.density, dt=scene.render.fps_base / scene.render.fps, substeps=s.substeps,
                        gravity=gravity, mass_damping=s.mass_damping, stiffness_damping=s.stiffness_damping)
    pin(sim, cage, pinned_nodes(cage))
    return sim, np.linalg.inv(M)


def pin(sim, cage, pins):
    """Holds the pinned nodes, or moves them by the cage's rigid motion (times from the first frame)."""
    s = cage.mbi
    if s.pin_motion == "held":
        if len(pins):
            sim.fix(pins)
        return
    if not len(pins):
        raise ValueError("the cage %s has a rigid motion of its pinned nodes but no pinned group" % cage.name)
    if s.pin_rate != 0 and np.linalg.norm(s.pin_axis) == 0:
        raise ValueError("the cage %s's pinned rotation has a zero axis" % cage.name)
    stop = s.pin_stop if s.pin_stop > 0 else 1e300
    if stop < s.pin_start:
        raise ValueError("the cage %s's pinned motion stops (%g s) before it starts (%g s)"
                         % (cage.name, s.pin_stop, s.pin_start))
    axis = tuple(s.pin_axis) if np.linalg.norm(s.pin_axis) > 0 else (0.0, 0.0, 1.0)
    sim.add_kinematic(pins, center=tuple(s.pin_center), axis=axis, angular_velocity=s.pin_rate,
                      velocity=tuple(s.pin_velocity), start=s.pin_start, stop=stop)


def simulate_job(scene, cage, start, end, directory):
    """Checks the request, then returns the job: simulate, cache the cage, bake its bound meshes."""
    if cage is None or not cage.mbi.is_cage:
        raise ValueError("make the mbi cage the active object")
    if end <= start:
        raise ValueError("the frame range %d..%d has no step" % (start, end))
    sim, to_local = simulator(scene, cage)
    folder = bake.cache_folder(directory)
    models = [o for o in scene.objects if o.type == "MESH" and o.mbi.cage == cage and not o.mbi.baked]
    return _steps(scene, cage, sim, to_local, start, end, folder, models)


def _steps(scene, cage, sim, to_local, start, end, folder, models):
    samples = end - start + 1
    share = 0.5 if models else 1.0  # of the progress bar: the simulation, then the bake
    path = bake.cache_path(folder, cage)
    writer, committed, done = pc2.Writer(path, sim.nodes, samples, float(start)), False, False
    try:
        for i in range(samples):
            if i > 0:
                result = sim.step()
                if not result:
                    raise ValueError("frame %d: the simulation failed: %s" % (start + i, result.message))
            X = sim.positions
            writer.write(X @ to_local[:3, :3].T + to_local[:3, 3])
            yield share * (i + 1) / samples
        writer.commit()
        committed = True
        bake.attach_cache(cage, bpy.path.relpath(path) if bpy.data.filepath else path, start)
        for fraction in bake.bake_steps(scene, models, start, end, [bake.cache_path(folder, m) for m in models]):
            yield share + (1 - share) * fraction
        done = True
    finally:
        writer.discard()
        if not done and committed:  # the meshes' bake failed or was cancelled: no cage cache either
            if live.CACHE_MODIFIER in cage.modifiers:
                cage.modifiers.remove(cage.modifiers[live.CACHE_MODIFIER])
            os.remove(path)


class MBI_OT_simulate(jobs.ModalJob, bpy.types.Operator):
    """Simulate the active mbi cage (FEM) over the scene's frame range and bake its bound meshes (Esc cancels)"""
    bl_idname = "mbi.simulate"
    bl_label = "Simulate and bake mbi cage"
    bl_options = {"REGISTER", "UNDO"}

    directory: bpy.props.StringProperty(name="Folder", default="//mbi_cache", subtype="DIR_PATH")
    frame_start: bpy.props.IntProperty(name="Start", default=-1,
                                       description="First frame, the rest state (-1: the scene's)")
    frame_end: bpy.props.IntProperty(name="End", default=-1, description="Last frame (-1: the scene's)")

    def make_job(self, context):
        scene = context.scene
        start = scene.frame_start if self.frame_start < 0 else self.frame_start
        end = scene.frame_end if self.frame_end < 0 else self.frame_end
        return simulate_job(scene, context.active_object, start, end, self.directory)


def register():
    bpy.utils.register_class(MBI_OT_simulate)


def unregister():
    bpy.utils.unregister_class(MBI_OT_simulate)
