"""Inside `blender -b --factory-startup`: Blender objects marked as mbi colliders touch a simulated
model's surface. A ball (bound to its cage) falls onto a plane object and is pushed by a sphere
object keyed to move at constant velocity; the baked ball equals `mbi run`'s pipeline of a scene with
the same data (contact = "surface", the same [[colliders]] and motion; FramePipeline.from_scene) at
every frame, and stays on the colliders' approach side. A collider overlapping the ball at rest, and one whose keys are not a
constant-velocity motion, are refused with their messages and leave no cache. The shapes fitted from
objects (plane, sphere, box, capsule) and their signed distances agree with mbi.Collider's; a cube
as a mesh collider (its own triangles) measures as the box within a voxel.

    blender -b --factory-startup --python contact.py -- <work dir> <mbi executable>
"""
import os
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import check, fail, positions, run_main, select_only, write_scene  # noqa: E402

START, END, FPS = 1, 25, 24
MATERIAL = dict(young=2e4, poisson=0.4, density=500.0, mass_damping=1.0)
# binary-exact numbers: Blender stores float32, and the contact's Newton (20 iterations at most) is
# sensitive to the last bit of its input; the scene file then holds exactly what the add-on reads
GROUND, FRICTION = 0.25, 0.375
BALL = dict(radius=0.25, start=(1.0, 0.0, 0.75), velocity=(-0.75, 0.0, 0.0), first=9, last=21)
PENETRATION = 2e-3  # of the model's size: the penalty contact's sinking allowed at any frame


def setup():
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=0.5, location=(0.0, 0.0, 1.0))
    model = bpy.context.active_object
    model.name = "model"
    bpy.ops.object.transform_apply(location=True)  # world = local: the scene file takes the same numbers
    bpy.ops.mbi.cage(vertices=150)
    cage = bpy.context.active_object
    for name, value in MATERIAL.items():
        setattr(cage.mbi, name, value)
    select_only([model, cage], cage)
    bpy.ops.mbi.bind()
    bpy.ops.mesh.primitive_plane_add(size=6.0, location=(0.0, 0.0, GROUND))
    ground = bpy.context.active_object
    ground.name = "ground"
    ground.mbi.collider, ground.mbi.friction = "plane", FRICTION
    bpy.ops.mesh.primitive_uv_sphere_add(radius=BALL["radius"], location=BALL["start"])
    pusher = bpy.context.active_object
    pusher.name = "pusher"
    pusher.mbi.collider = "sphere"
    key_linear(pusher)
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = FPS, START, END
    return model, cage, ground, pusher


def key_linear(obj):
    """Keys the object's location from BALL's first to last frame at BALL's velocity, linearly."""
    obj.location = BALL["start"]
    obj.keyframe_insert("location", frame=BALL["first"])
    obj.location = np.array(BALL["start"]) + np.array(BALL["velocity"]) * (BALL["last"] - BALL["first"]) / FPS
    obj.keyframe_insert("location", frame=BALL["last"])
    for curve in obj.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def shapes():
    """Fitted shapes of a rotated, scaled cube as a box and as a capsule."""
    from mbi_blender import colliders
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(5.0, 1.0, 2.0), rotation=(0.3, 0.0, 0.7),
                                    scale=(1.0, 2.0, 0.5))
    cube = bpy.context.active_object
    cube.mbi.collider = "box"
    bpy.context.view_layer.update()
    M = np.array(cube.matrix_world)
    box = colliders.shape(cube, M)
    check(np.allclose(box["half_extents"], (1.0, 2.0, 0.5), atol=1e-6) and np.allclose(box["center"], M[:3, 3])
          and np.allclose(box["axes"], (M[:3, :3] / np.linalg.norm(M[:3, :3], axis=0)).T),
          "a rotated, scaled cube fits the box of its half extents and axes")
    cube.mbi.collider = "capsule"
    capsule = colliders.shape(cube, M)
    check(abs(capsule["radius"] - 1.0) < 1e-6 and abs(np.linalg.norm(capsule["b"] - capsule["a"]) - 2.0) < 1e-6,
          "the same cube as a capsule: radius 1 along its longest axis, segment 2")
    mesh_like_box(cube, M, box)
    bpy.data.objects.remove(cube)


def mesh_like_box(cube, M, box):
    """The cube as a mesh collider (its own triangles, a level set) measures as the fitted box, within a
    voxel, at points near its faces; moved by its keys as the other shapes are."""
    from mbi_blender import colliders, module
    mbi = module.load()
    cube.mbi.collider = "mesh"
    mesh, fitted, _ = colliders.make(mbi, cube, [M, M], 1.0 / FPS, START)
    check(mesh.shape == "mesh" and fitted["F"].shape == (12, 3), "the cube as a mesh collider: 12 triangles")
    exact = mbi.Collider.box(box["center"], box["half_extents"], box["axes"])
    rng = np.random.default_rng(3)
    corners = np.array([tuple(v) for v in cube.bound_box])
    half = (corners.max(axis=0) - corners.min(axis=0)) / 2  # the mesh's, its center at the origin
    local = rng.uniform(-1.0, 1.0, (400, 3))
    local[np.arange(400), rng.integers(0, 3, 400)] = rng.choice([-1.0, 1.0], 400)  # on a face
    P = (local * half) @ M[:3, :3].T + M[:3, 3]
    P += rng.uniform(-0.05, 0.05, (400, 1)) * exact.distances(P)[1]  # off it along the normal
    voxel = np.linalg.norm(np.ptp(fitted["V"], axis=0)) / 128
    error = np.abs(mesh.distances(P)[0] - exact.distances(P)[0]).max()
    check(error <= voxel, "the mesh collider's distances are the box's within a voxel (%.2e <= %.2e m)"
          % (error, voxel))


def refused(cage, model, what, expected):
    select_only([cage], cage)
    try:
        bpy.ops.mbi.simulate()
        fail("%s was simulated" % what)
    except RuntimeError as error:
        check(expected in str(error), "%s is refused: %s" % (what, str(error).strip()))
    folder = os.path.join(os.path.dirname(bpy.data.filepath), "mbi_cache")
    left = os.listdir(folder) if os.path.isdir(folder) else []
    check(not left and "mbi cache" not in cage.modifiers and "mbi cache" not in model.modifiers,
          "and leaves no cache (folder holds %s)" % left)


def bad_input(cage, model, ground, pusher):
    ground.location.z = 0.6  # through the ball's bottom
    refused(cage, model, "a collider overlapping the model at rest", "overlaps model at rest")
    ground.location.z = GROUND
    for curve in pusher.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "BEZIER"
    refused(cage, model, "a collider keyed with ease in and out", "constant-velocity")
    for curve in pusher.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def sphere_of(obj):
    """The sphere of the object's bounding box as Blender stores it (float32 corners; a UV sphere's are not
    symmetric to the last bit): center and largest half extent, in world space at its first pose."""
    corners = np.array([tuple(v) for v in obj.bound_box], dtype=np.float64)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    M = np.array(obj.matrix_world)
    return M[:3, :3] @ ((lo + hi) / 2) + M[:3, 3], float(((hi - lo) / 2).max())


def mbi_run(mbi, exe, work, model, cage):
    bpy.context.scene.frame_set(START)
    pusher = bpy.data.objects["pusher"]
    center, radius = sphere_of(pusher)
    origin = tuple(map(float, pusher.matrix_world.translation))  # the add-on's center of its motion
    dt = 1.0 / FPS
    material = dict(young=cage.mbi.young, poisson=cage.mbi.poisson, density=cage.mbi.density,
                    mass_damping=cage.mbi.mass_damping)  # as Blender keeps them (float32)
    colliders = """contact = "surface"
[[colliders]]
shape = "plane"
point = [0, 0, %r]
normal = [0, 0, 1]
friction = %r
[[colliders]]
shape = "sphere"
center = [%r, %r, %r]
radius = %r
motion = { velocity = [%r, %r, %r], twist_center = [%r, %r, %r], start = %r, stop = %r }""" % (
        GROUND, FRICTION, *map(float, center), radius, *BALL["velocity"], *origin, (BALL["first"] - START) * dt,
        (BALL["last"] - START) * dt)
    path = write_scene(mbi, work, "blender-contact", model, cage, material, dt, END - START, colliders)
    # mbi run's pipeline from the same module as the add-on's (its frames equal mbi run's: test_contact.py):
    # the contact's Newton stops at its iteration cap here, so a build of another tree differs in the last bits
    return mbi.FramePipeline.from_scene(path).run(END - START + 1)


def approach_side(baked, size):
    """The baked model against the colliders as Blender poses them, frame by frame."""
    deepest, gap, pushed = np.inf, np.inf, np.inf
    for frame in range(START, END + 1):
        bpy.context.scene.frame_set(frame)
        center = np.array(bpy.data.objects["pusher"].matrix_world.translation)
        P = baked[frame - START]
        d_ground, d_sphere = P[:, 2] - GROUND, np.linalg.norm(P - center, axis=1) - BALL["radius"]
        deepest = min(deepest, d_ground.min(), d_sphere.min())
        gap, pushed = min(gap, d_ground.min()), min(pushed, d_sphere.min())
    check(deepest >= -PENETRATION * size, "the baked model stays on the colliders' approach side at every frame "
          "(deepest %.2e of its size, allowed %.0e)" % (-deepest / size, PENETRATION))
    check(gap < 0.01 * size and pushed < 0.01 * size,
          "it touched both: the ground (%.2e) and the moving sphere (%.2e of its size)" % (gap / size, pushed / size))


def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    shapes()
    model, cage, ground, pusher = setup()
    rest = positions(model.data)
    size = np.linalg.norm(np.ptp(rest, axis=0))
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(work, "contact.blend"))
    model, cage = bpy.data.objects["model"], bpy.data.objects[cage.name]
    ground, pusher = bpy.data.objects["ground"], bpy.data.objects["pusher"]
    bad_input(cage, model, ground, pusher)

    select_only([cage], cage)
    check(bpy.ops.mbi.simulate() == {"FINISHED"}, "the simulate operator ran frames %d..%d with 2 colliders"
          % (START, END))
    expected = mbi_run(mbi, exe, work, model, cage)
    baked = mbi.read_point_cache(bpy.path.abspath(model.modifiers["mbi cache"].filepath)).frames
    check(baked.shape == expected.shape, "as many frames as the scene's run (%d)" % len(baked))
    error = np.abs(baked - expected).max() / size
    check(error <= 1e-6, "the baked model equals mbi run's pipeline of the scene at every frame (%.2e of its size)"
          % error)
    approach_side(baked, size)
    moved = np.abs(baked[-1] - rest).max() / size
    check(moved > 0.1, "the model moved (%.2f of its size)" % moved)
    print("PASS")


if __name__ == "__main__":
    run_main(main)
