"""Physics: mbi's co-rotational FEM (mbi.Simulator) moves the cage over a frame range; the cage's
motion is baked to a PC2 played by a Mesh Cache modifier on the cage, then the bound meshes are
baked from it as by the bake operator.

The simulation runs in world space (a Blender unit is a metre), one step of 1/fps s a frame, the
scene's gravity; the first frame of the range is the rest state. Nodes of the cage's pinned
vertex group (weight > 0) are held where they are, moved by a scripted rigid motion (velocity
and a rotation about an axis, from a start to a stop time: mbi's kinematic constraint), or carried
rigidly by an object's or a bone's animated transform (a kinematic motion set frame by frame).
Objects marked as mbi colliders touch the bound meshes' surface (FramePipeline.with_contact).
"""
import os

import bpy
import numpy as np

from . import bake, colliders, jobs, live, module, motion, pc2, storage


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


def simulator(scene, cage, contact_points=None):
    """mbi.Simulator of the cage's rest nodes in world space with the cage's settings and the scene's gravity;
    with contact_points (world), the Newton settings of a scene with contact = "surface"."""
    mbi = module.load()
    s = cage.mbi
    M = np.array(cage.matrix_world)
    U = storage.positions(cage.data).astype(np.float64) @ M[:3, :3].T + M[:3, 3]
    gravity = tuple(scene.gravity) if scene.use_gravity else (0.0, 0.0, 0.0)
    dt = scene.render.fps_base / scene.render.fps
    newton = {}
    if contact_points is not None:
        diagonal = np.linalg.norm(np.ptp(contact_points, axis=0))
        newton = dict(newton_iterations=20, newton_tolerance=1e-5 * diagonal / (dt / s.substeps))
    sim = mbi.Simulator(U, storage.tets(cage.data), youngs_modulus=s.young, poisson_ratio=s.poisson,
                        density=s.density, dt=dt, substeps=s.substeps, gravity=gravity, mass_damping=s.mass_damping,
                        stiffness_damping=s.stiffness_damping, **newton)
    return sim, U, np.linalg.inv(M)


def pin(sim, cage, pins):
    """Holds the pinned nodes, or moves them by the cage's rigid motion (times from the first frame); the
    motion of "Follow object" is set frame by frame (Follower)."""
    s = cage.mbi
    if s.pin_motion == "held":
        if len(pins):
            sim.fix(pins)
        return
    if not len(pins):
        raise ValueError("the cage %s moves its pinned nodes but has no pinned group" % cage.name)
    if s.pin_motion == "object":
        return
    if s.pin_rate != 0 and np.linalg.norm(s.pin_axis) == 0:
        raise ValueError("the cage %s's pinned rotation has a zero axis" % cage.name)
    stop = s.pin_stop if s.pin_stop > 0 else 1e300
    if stop < s.pin_start:
        raise ValueError("the cage %s's pinned motion stops (%g s) before it starts (%g s)"
                         % (cage.name, s.pin_stop, s.pin_start))
    axis = tuple(s.pin_axis) if np.linalg.norm(s.pin_axis) > 0 else (0.0, 0.0, 1.0)
    sim.add_kinematic(pins, center=tuple(s.pin_center), axis=axis, angular_velocity=s.pin_rate,
                      velocity=tuple(s.pin_velocity), start=s.pin_start, stop=stop)


def pin_source(cage):
    """The world matrix (4x4) the pinned nodes follow, as a function of the depsgraph (an object or a bone)."""
    s = cage.mbi
    target = s.pin_object
    if target is None:
        raise ValueError("the cage %s's pinned nodes follow an object: choose the object" % cage.name)
    if not s.pin_bone:
        return lambda depsgraph: np.array(target.evaluated_get(depsgraph).matrix_world)
    if target.type != "ARMATURE" or s.pin_bone not in target.pose.bones:
        raise ValueError("the cage %s's pinned nodes follow the bone %s, which %s does not have"
                         % (cage.name, s.pin_bone, target.name))
    bone = s.pin_bone

    def matrix(depsgraph):
        evaluated = target.evaluated_get(depsgraph)
        return np.array(evaluated.matrix_world) @ np.array(evaluated.pose.bones[bone].matrix)
    return matrix


def record(scene, start, end, sources):
    """Each source's world matrix (a function of the depsgraph) at frames start..end; the live path paused."""
    before, out = scene.frame_current, [[] for _ in sources]
    with live.paused():
        try:
            for frame in range(start, end + 1):
                scene.frame_set(frame)
                depsgraph = bpy.context.evaluated_depsgraph_get()
                for poses, source in zip(out, sources):
                    poses.append(source(depsgraph))
        finally:
            scene.frame_set(before)
    return out


class Follower:
    """Pinned nodes carried rigidly by recorded poses: before the step to frame i, a kinematic motion
    taking them from pose i - 1 to pose i over that frame (motion.step), the one before removed."""

    def __init__(self, sim, pins, poses, dt, name, start):
        self.sim, self.pins, self.dt, self.handle = sim, pins, dt, None
        self.steps = []
        for i in range(1, len(poses)):
            try:
                self.steps.append(motion.relative(poses[i], poses[i - 1]))
            except ValueError as error:
                raise ValueError("the object the pinned nodes follow (%s) at frame %d %s"
                                 % (name, start + i, error)) from None

    def before_step(self, i):
        if self.handle is not None:
            self.sim.remove(self.handle)
        center = self.sim.positions[self.pins].mean(axis=0)
        m = motion.step(self.steps[i - 1], center, (i - 1) * self.dt, self.dt)
        self.handle = self.sim.add_kinematic(self.pins, center=tuple(m["center"]), axis=tuple(m["axis"]),
                                             angular_velocity=m["rate"], velocity=tuple(m["velocity"]),
                                             start=m["start"], stop=m["stop"])


def contact_pipeline(mbi, scene, cage, sim, U, models, points, marked, poses, start):
    """The FramePipeline stepping sim with contact at the models' points against the marked colliders
    (posed by poses, one list of matrices each), or None without colliders. Refuses a collider that
    overlaps a model at rest."""
    if not marked:
        return None
    if not models:
        raise ValueError("colliders act on the surface of bound meshes: bind a mesh to the cage %s" % cage.name)
    methods = {(m.mbi.method, m.mbi.alpha) for m in models}
    if len(methods) > 1:
        raise ValueError("contact takes one method: the meshes bound to %s use %s" % (cage.name, sorted(methods)))
    made = []
    for obj, matrices in zip(marked, poses):
        collider, _, _ = colliders.make(mbi, obj, matrices, sim.dt, start)
        colliders.check_apart(obj, collider, list(zip([m.name for m in models], points)))
        made.append(collider)
    method, alpha = methods.pop()
    try:
        return mbi.FramePipeline.with_contact(U, storage.tets(cage.data), np.concatenate(points), sim, made,
                                              stiffness=cage.mbi.contact_stiffness or None, method=method,
                                              alpha=alpha or None)
    except mbi.Error as error:
        raise ValueError("contact: %s" % error) from error


def world_rest(model):
    M = np.array(model.matrix_world)
    return storage.positions(model.data).astype(np.float64) @ M[:3, :3].T + M[:3, 3]


def simulate_job(scene, cage, start, end, directory):
    """Checks the request, then returns the job: simulate, cache the cage, bake its bound meshes."""
    if cage is None or not cage.mbi.is_cage:
        raise ValueError("make the mbi cage the active object")
    if end <= start:
        raise ValueError("the frame range %d..%d has no step" % (start, end))
    mbi = module.load()
    models = [o for o in scene.objects if o.type == "MESH" and o.mbi.cage == cage and not o.mbi.baked]
    points = [world_rest(m) for m in models]
    marked = colliders.marked(scene)
    sim, U, to_local = simulator(scene, cage, np.concatenate(points) if marked and points else None)
    pins = pinned_nodes(cage)
    pin(sim, cage, pins)
    follows = cage.mbi.pin_motion == "object"
    sources = ([pin_source(cage)] if follows else []) + [
        lambda depsgraph, o=o: np.array(o.evaluated_get(depsgraph).matrix_world) for o in marked]
    poses = record(scene, start, end, sources) if sources else []
    follower = Follower(sim, pins, poses.pop(0), sim.dt, cage.mbi.pin_object.name, start) if follows else None
    pipe = contact_pipeline(mbi, scene, cage, sim, U, models, points, marked, poses, start)
    folder = bake.cache_folder(directory)
    return _steps(scene, cage, Stepper(sim, pipe, follower), to_local, start, end, folder, models)


class Stepper:
    """One frame of the simulation: the follower's motion, then the simulator's step (through the contact
    pipeline when there is one; its first step is the rest frame)."""

    def __init__(self, sim, pipe, follower):
        self.sim, self.pipe, self.follower = sim, pipe, follower

    def frame(self, i, frame):
        if i > 0 and self.follower is not None:
            self.follower.before_step(i)
        if self.pipe is not None:
            result = self.pipe.step(evaluate=False)
            if not result.ok:
                raise ValueError("frame %d: the simulation failed: %s" % (frame, result.message))
        elif i > 0:
            result = self.sim.step()
            if not result:
                raise ValueError("frame %d: the simulation failed: %s" % (frame, result.message))
        return self.sim.positions


def _steps(scene, cage, stepper, to_local, start, end, folder, models):
    samples = end - start + 1
    share = 0.5 if models else 1.0  # of the progress bar: the simulation, then the bake
    path = bake.cache_path(folder, cage)
    writer, committed, done = pc2.Writer(path, stepper.sim.nodes, samples, float(start)), False, False
    try:
        for i in range(samples):
            X = stepper.frame(i, start + i)
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
