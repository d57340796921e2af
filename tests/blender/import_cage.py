"""Inside `blender -b --factory-startup`: tetrahedral meshes from tests/data (.msh, .vtk, .node/.ele)
imported as cages hold the file's nodes and tetrahedra; a model bound to one follows its animation
(equal to `mbi deform`); a surface-only .msh and a file with a flat tetrahedron are refused by name
and leave no object.

    blender -b --factory-startup --python import_cage.py -- <work dir> <mbi executable>
"""
import os
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import check, evaluated, fail, mbi_deform, positions, run_main, select_only, tets  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
FILES = ("gmsh/box-41.msh", "gmsh/box.vtk", "vtu/box.node")


def imported(mbi, name):
    path = os.path.join(DATA, name)
    check(bpy.ops.mbi.import_cage(filepath=path) == {"FINISHED"}, "%s imported" % name)
    cage = bpy.context.active_object
    expected = mbi.read_control_mesh(path)
    check(cage.mbi.is_cage and np.array_equal(positions(cage.data), expected.U.astype(np.float32))
          and np.array_equal(tets(cage), expected.T),
          "%s: the cage holds the file's %d nodes and %d tetrahedra" % (name, len(expected.U), len(expected.T)))
    return cage


def refused(name, words):
    count = len(bpy.data.objects)
    try:
        bpy.ops.mbi.import_cage(filepath=os.path.join(DATA, name))
        fail("%s was imported" % name)
    except RuntimeError as error:
        message = str(error).strip()
        stem = os.path.splitext(os.path.basename(name))[0] + "."  # TetGen's message may name the .ele
        check(stem in message and words in message, "%s is refused: %s" % (name, message))
    check(len(bpy.data.objects) == count, "%s left no object" % name)


def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    cages = [imported(mbi, name) for name in FILES]
    cage = cages[0]
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=0.35, location=(0.5, 0.5, 1.0))
    model = bpy.context.active_object
    rest_model = evaluated(model)
    size = np.linalg.norm(np.ptp(rest_model, axis=0))
    select_only([model, cage], cage)
    check(bpy.ops.mbi.bind() == {"FINISHED"}, "a model bound to the imported cage")
    U, T = positions(cage.data), tets(cage)
    cage.shape_key_add(name="Basis", from_mix=False)
    pose = cage.shape_key_add(name="pose", from_mix=False)
    X = U + 0.2 * np.stack([np.sin(2 * U[:, 2]), U[:, 0] * U[:, 2], np.cos(3 * U[:, 1])], axis=1)
    pose.data.foreach_set("co", X.astype(np.float32).ravel())
    pose.value = 1.0
    bpy.context.view_layer.update()
    P = evaluated(model)
    expected = mbi_deform(mbi, exe, work, U, T, rest_model, evaluated(cage), "imported")
    error = np.abs(P - expected).max() / size
    check(np.abs(P - rest_model).max() / size > 0.05 and error <= 1e-6,
          "the model follows the imported cage as mbi deform does (%.2e of its size)" % error)
    refused("gmsh/surface-only.msh", "no tetrahedra")
    refused("bad/geometry/flat.node", "degenerate")
    print("PASS")


if __name__ == "__main__":
    run_main(main)
