"""Inside `blender -b --factory-startup`: only the cage's boundary is animated (a shape key bending it
by 90 degrees); the interior nodes follow by the harmonic extension, equal to an independent solve
(mbi's element gradients, the full Dirichlet system), no tetrahedron inverts, and Blender's evaluated
model equals `mbi deform` with those nodes; with the cage's setting "as animated" the interior stays.

    blender -b --factory-startup --python interior.py -- <work dir> <mbi executable>
"""
import os
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import check, evaluated, mbi_deform, positions, run_main, select_only, tets  # noqa: E402


def bend(U, fraction):
    """A bend of the x axis about y, `fraction` of 90 degrees over the nodes' x extent."""
    lo, hi = U[:, 0].min(), U[:, 0].max()
    c = U.mean(axis=0)
    length = hi - lo
    radius = length / (fraction * np.pi / 2)
    theta = (U[:, 0] - c[0]) / radius
    r = radius - (U[:, 2] - c[2])
    X = U.copy()
    X[:, 0] = c[0] + r * np.sin(theta)
    X[:, 2] = c[2] + radius - r * np.cos(theta)
    return X


def independent_extension(mbi, U, T, X):
    """The interior nodes by the full Dirichlet problem of the P1 stiffness assembled from mbi's gradients."""
    G = mbi.embed(U, T, U[:1]).gradients.reshape(-1, 4, 3)
    E = U[T[:, 1:]] - U[T[:, :1]]
    volume = np.abs(np.einsum("mi,mi->m", E[:, 0], np.cross(E[:, 1], E[:, 2]))) / 6
    K = np.zeros((len(U), len(U)))
    for a in range(4):
        for b in range(4):
            np.add.at(K, (T[:, a], T[:, b]), volume * np.einsum("mk,mk->m", G[:, a], G[:, b]))
    boundary = np.unique(mbi.boundary_faces(U, T))
    interior = np.setdiff1d(np.arange(len(U)), boundary)
    D = np.zeros_like(U)
    D[boundary] = X[boundary] - U[boundary]
    D[interior] = np.linalg.solve(K[np.ix_(interior, interior)], -K[np.ix_(interior, boundary)] @ D[boundary])
    return U + D, interior


def signed_volumes(X, T):
    E = X[T[:, 1:]] - X[T[:, :1]]
    return np.einsum("mi,mi->m", E[:, 0], np.cross(E[:, 1], E[:, 2]))


def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
    model = bpy.context.active_object
    model.scale = (2.0, 0.5, 0.5)
    bpy.context.view_layer.update()
    rest_model = evaluated(model)
    size = np.linalg.norm(np.ptp(rest_model, axis=0))
    bpy.ops.mbi.cage(vertices=300)
    cage = bpy.context.active_object
    select_only([model, cage], cage)
    bpy.ops.mbi.bind()
    U, T = positions(cage.data), tets(cage)
    boundary = np.unique(mbi.boundary_faces(U, T))
    cage.shape_key_add(name="Basis", from_mix=False)
    key = cage.shape_key_add(name="bend", from_mix=False)
    X = U.copy()
    X[boundary] = bend(U, 1.0)[boundary]
    key.data.foreach_set("co", X.astype(np.float32).ravel())
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=11)

    for frame in (6, 11):
        X_blender = evaluated(cage, frame)
        expected, interior = independent_extension(mbi, U, T, X_blender)
        check(np.array_equal(X_blender[interior], U[interior]), "frame %d: only the boundary is animated" % frame)
        moved = np.linalg.norm(expected[interior] - U[interior], axis=1).max() / size
        check(moved > 0.05, "frame %d: the interior nodes follow (moved %.3f of the model's size)" % (frame, moved))
        volumes = signed_volumes(expected, T) * np.sign(signed_volumes(U, T))
        check(volumes.min() > 0, "frame %d: no tetrahedron inverts (smallest volume %.2e of its rest mean)"
              % (frame, volumes.min() / np.abs(signed_volumes(U, T)).mean()))
        P = evaluated(model)
        deformed = mbi_deform(mbi, exe, work, U, T, rest_model, expected, "bend%d" % frame)
        error = np.abs(P - deformed).max() / size
        check(error <= 1e-6, "frame %d: the model equals mbi deform with the extended interior (%.2e of its size)"
              % (frame, error))

    cage.mbi.interior = "animated"
    bpy.context.scene.frame_set(10)
    P = evaluated(model, 11)
    at_rest = mbi_deform(mbi, exe, work, U, T, rest_model, evaluated(cage), "animated")
    error = np.abs(P - at_rest).max() / size
    check(error <= 1e-6, "'as animated': the interior stays where Blender put it (%.2e of the size)" % error)
    print("PASS")


if __name__ == "__main__":
    run_main(main)
