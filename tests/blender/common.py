"""Helpers of the add-on's tests inside Blender: checks, positions, selection, `mbi deform`."""
import os
import subprocess
import sys

import bpy
import numpy as np


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)
    print("ok: " + message)


def world(obj, local):
    M = np.array(obj.matrix_world)
    return local @ M[:3, :3].T + M[:3, 3]


def positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def tets(cage):
    return np.asarray(cage.data["mbi_tets"].to_list()).reshape(-1, 4)


def select_only(objects, active):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = active


def evaluated(obj, frame=None):
    """The object's evaluated vertices in world space at a frame (None: as it is)."""
    if frame is not None:
        bpy.context.scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    return world(obj, positions(obj.evaluated_get(depsgraph).data))


def mbi_deform(mbi, exe, work, U, T, rest_model, X, tag):
    """`mbi deform` of the model's rest points by the cage (U, T) deformed to X."""
    base = os.path.join(work, "cage_" + tag)
    mbi.write_tetgen(base, U, T)
    np.savetxt(os.path.join(work, "x_%s.txt" % tag), X, fmt="%.17g")
    mbi.write_points(os.path.join(work, "model_%s.txt" % tag), rest_model)
    out = os.path.join(work, "out_%s.txt" % tag)
    run = subprocess.run([exe, "deform", "--control", base, "--deformed", os.path.join(work, "x_%s.txt" % tag),
                          "--mesh", os.path.join(work, "model_%s.txt" % tag), "--out", out, "--force"],
                         capture_output=True, text=True)
    if run.returncode != 0:
        fail("mbi deform: " + run.stderr)
    return mbi.read_points(out)


def bound_sphere(subdivisions, location=(0.0, 0.0, 0.0), scale=None):
    """An ico sphere "model" (radius 1) bound to a 150-node cage made around it: (model, cage)."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions, radius=1.0, location=location)
    model = bpy.context.active_object
    model.name = "model"
    if scale is not None:
        model.scale = scale
        bpy.context.view_layer.update()
    bpy.ops.mbi.cage(vertices=150)
    cage = bpy.context.active_object
    select_only([model, cage], cage)
    bpy.ops.mbi.bind()
    return model, cage


def pose_key(cage, X):
    """A Basis key and a shape key "pose" holding the node positions X (value 0): the key."""
    cage.shape_key_add(name="Basis", from_mix=False)
    pose = cage.shape_key_add(name="pose", from_mix=False)
    pose.data.foreach_set("co", X.astype(np.float32).ravel())
    return pose


def agrees_with_mbi_deform(mbi, exe, work, model, cage, tag):
    """Checks the model's evaluated positions against `mbi deform` of its rest by the cage's (1e-6 of its size);
    returns the evaluated positions and the model's size."""
    P = evaluated(model)
    expected = mbi_deform(mbi, exe, work, positions(cage.data), tets(cage), positions(model.data),
                          evaluated(cage), tag)
    size = np.linalg.norm(np.ptp(P, axis=0))
    error = np.abs(P - expected).max() / size
    check(error <= 1e-6, "%s: the model equals mbi deform on the current rest (%.2e of its size)" % (tag, error))
    return P, size


SCENE = """name = "%s"
[dense]
path = "model.obj"
[control]
path = "cage"
[material]
young = %r
poisson = %r
density = %r
[simulation]
dt = %r
frames = %d
gravity = [%r, %r, %r]
damping_mass = %r
%s
[interpolation]
gpu = "off"
[output]
mesh_format = "none"
control_vtk = false
image = false
metrics = false
"""


def write_scene(mbi, work, name, model, cage, material, dt, frames, rest):
    """The bound model (model.obj) and the cage (cage.node/.ele) as Blender holds them, and scene.toml that
    simulates them (material: young, poisson, density, mass_damping; the scene's gravity; `rest`: the lines
    after [simulation]'s keys). Returns the scene's path."""
    mbi.write_tetgen(os.path.join(work, "cage"), positions(cage.data), tets(cage))
    F = np.empty(len(model.data.polygons) * 3, dtype=np.int32)
    model.data.polygons.foreach_get("vertices", F)
    mbi.write_surface(os.path.join(work, "model.obj"), positions(model.data), F.reshape(-1, 3))
    path = os.path.join(work, "scene.toml")
    with open(path, "w") as f:
        f.write(SCENE % (name, material["young"], material["poisson"], material["density"], dt, frames,
                         *tuple(bpy.context.scene.gravity), material["mass_damping"], rest))
    return path


def run_main(main):
    """Runs main(*arguments after --); any exception is a failure with its message, not Blender's exit 0."""
    args = sys.argv[sys.argv.index("--") + 1:]
    try:
        main(*args)
    except Exception as error:  # noqa: BLE001
        import traceback
        traceback.print_exc()
        fail("%s: %s" % (type(error).__name__, error))
    sys.exit(0)
