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
from common import (  # noqa: E402
    agrees_with_mbi_deform, bound_sphere, check, pose_key, positions, run_main, select_only,
    tets)


def source_file(work):
    """A model bound to a posed cage, saved; returns the file, the cage's name and its tetrahedra."""
    model, cage = bound_sphere(3)
    U = positions(cage.data)
    pose = pose_key(cage, U + 0.25 * np.stack([U[:, 1] ** 2, U[:, 2], -U[:, 0] * U[:, 2]], axis=1))
    pose.value = 1.0
    path = os.path.join(work, "source.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return path, cage.name, tets(cage)


def agrees(mbi, exe, work, model, cage, tag):
    P, size = agrees_with_mbi_deform(mbi, exe, work, model, cage, tag)
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
