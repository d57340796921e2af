"""Inside `blender -b --factory-startup`: a cage and its bound model appended from another .blend into a
file that already holds an object of the cage's name keep the tetrahedra and the binding (the model
equals `mbi deform` of the posed, renamed cage), and the appended cage binds a new mesh.

    blender -b --factory-startup --python append.py -- <work dir> <mbi executable>
"""
import os
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import check, evaluated, mbi_deform, positions, run_main, select_only, tets  # noqa: E402


def source_file(work):
    """A model bound to a posed cage, saved; returns the file, the cage's name and its tetrahedra."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.0)
    model = bpy.context.active_object
    model.name = "model"
    bpy.ops.mbi.cage(vertices=150)
    cage = bpy.context.active_object
    select_only([model, cage], cage)
    bpy.ops.mbi.bind()
    U = positions(cage.data)
    cage.shape_key_add(name="Basis", from_mix=False)
    pose = cage.shape_key_add(name="pose", from_mix=False)
    pose.data.foreach_set("co", (U + 0.25 * np.stack([U[:, 1] ** 2, U[:, 2], -U[:, 0] * U[:, 2]], axis=1))
                          .astype(np.float32).ravel())
    pose.value = 1.0
    path = os.path.join(work, "source.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return path, cage.name, tets(cage)


def agrees(mbi, exe, work, model, cage, tag):
    P = evaluated(model)
    expected = mbi_deform(mbi, exe, work, positions(cage.data), tets(cage), positions(model.data),
                          evaluated(cage), tag)
    size = np.linalg.norm(np.ptp(P, axis=0))
    error = np.abs(P - expected).max() / size
    check(error <= 1e-6, "%s: the model equals mbi deform (%.2e of its size)" % (tag, error))
    check(np.abs(P - positions(model.data)).max() / size > 0.01, "%s: and it is deformed" % tag)


def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    target = os.path.join(work, "target.blend")
    bpy.ops.wm.save_as_mainfile(filepath=target)
    source, cage_name, T = source_file(work)

    bpy.ops.wm.open_mainfile(filepath=target)
    bpy.ops.mesh.primitive_cube_add()
    bpy.context.active_object.name = cage_name  # the appended cage must take another name
    with bpy.data.libraries.load(source, link=False) as (_, data_to):
        data_to.objects = [cage_name, "model"]
    for obj in data_to.objects:
        bpy.context.collection.objects.link(obj)
    cage, model = data_to.objects
    check(cage.name != cage_name and cage.mbi.is_cage, "the appended cage is renamed %s" % cage.name)
    check(np.array_equal(tets(cage), T), "the appended cage keeps its %d tetrahedra" % len(T))
    check(model.mbi.cage == cage, "the appended model is bound to the appended cage")
    agrees(mbi, exe, work, model, cage, "appended")

    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.7)
    other = bpy.context.active_object
    select_only([other, cage], cage)
    check(bpy.ops.mbi.bind() == {"FINISHED"}, "a new mesh binds to the appended cage")
    agrees(mbi, exe, work, other, cage, "bound-to-appended")

    path = os.path.join(work, "target-saved.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    cage = next(o for o in bpy.data.objects if o.mbi.is_cage)
    check(np.array_equal(tets(cage), T), "saved and reopened, the appended cage keeps its tetrahedra")
    agrees(mbi, exe, work, bpy.data.objects["model"], cage, "appended-reopened")
    print("PASS")


if __name__ == "__main__":
    run_main(main)
