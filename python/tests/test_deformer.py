"""mbi.Deformer: the same results as the pieces it binds, batches equal to single poses, out=
arrays written in place without allocating dense arrays, normals, float32 results."""
import os
import tracemalloc

import numpy as np
import pytest

import mbi
import meshes

METHODS = ["bi", "modified-bi", "phong"]


@pytest.fixture(params=METHODS)
def method(request):
    return request.param


def unit_rows(A):
    return A / np.linalg.norm(A, axis=1, keepdims=True)


def test_deform_equals_its_pieces(mesh, method):
    U, T = mesh
    d = U.shape[1]
    P = meshes.points(U, 500)
    X = meshes.pose(U)
    deformer = mbi.Deformer(U, T, P, method=method)
    assert (deformer.dim, deformer.vertices, deformer.elements, deformer.points) == (d, len(U), len(T), 500)
    assert deformer.method == method
    emb = mbi.embed(U, T, P)
    assert np.array_equal(deformer.embedding.element, emb.element)
    M = {"bi": np.zeros((len(U) * d, d)), "phong": mbi.Phong(U, T).M(X), "modified-bi": mbi.ModifiedBI(U, T).solve(X)}[method]
    assert np.abs(deformer.M(X) - M).max() <= 1e-13 * (1 + np.abs(M).max())
    B = mbi.bezier_points(U, T, X, M)
    assert np.abs(deformer.bezier(X) - B).max() <= 1e-13 * (1 + np.abs(B).max())
    positions = deformer.deform(X)
    assert positions.shape == (500, d) and positions.dtype == np.float64 and positions.flags.c_contiguous
    assert np.abs(positions - meshes.reference(U, T, X, M, emb)).max() < 1e-12 * (1 + np.abs(X).max())
    if method == "modified-bi":
        assert deformer.alpha == mbi.default_alpha(d) and deformer.beta > 0 and deformer.memory_bytes > 0
        deformer.set_alpha(0.4)
        assert deformer.alpha == 0.4
        again = mbi.ModifiedBI(U, T, alpha=0.4)
        assert np.abs(deformer.deform(X) - mbi.evaluate(again.bezier(X, again.solve(X)), emb)).max() < 1e-12
    else:
        with pytest.raises(mbi.Error):
            deformer.alpha


def test_batch_equals_single_poses(mesh, method):
    U, T = mesh
    P = meshes.points(U, 300)
    deformer = mbi.Deformer(U, T, P, method=method)
    X = np.stack([meshes.pose(U, seed=s) for s in range(4)])
    batch = deformer.deform(X)
    assert batch.shape == (4, 300, U.shape[1])
    for k in range(4):
        assert np.array_equal(batch[k], deformer.deform(X[k]))
    G = np.random.default_rng(0).standard_normal(batch.shape)
    dX = deformer.vjp(G)
    assert dX.shape == X.shape
    for k in range(4):
        assert np.array_equal(dX[k], deformer.vjp(G[k]))
    # float32 batches, and a batch of one
    b32 = deformer.deform(X, dtype=np.float32)
    assert b32.dtype == np.float32 and np.abs(b32 - batch).max() < 1e-5
    assert np.array_equal(deformer.deform(X[:1])[0], batch[0])


def test_out_is_written_in_place(mesh):
    U, T = mesh
    d = U.shape[1]
    P = meshes.points(U, 400)
    deformer = mbi.Deformer(U, T, P, rest_normals=unit_rows(P - P.mean(0)))
    X = meshes.pose(U)
    expect, expect_n = deformer.deform(X, normals=True)
    out = np.empty((400, d))
    assert deformer.deform(X, out=out) is out
    assert np.array_equal(out, expect)
    fortran = np.empty((400, d), order="F")
    deformer.deform(X, out=fortran)
    assert np.array_equal(fortran, expect)
    # a strided slice of a larger array
    big = np.zeros((400, d + 2))
    deformer.deform(X, out=big[:, 1:d + 1])
    assert np.array_equal(big[:, 1:d + 1], expect) and not big[:, 0].any() and not big[:, -1].any()
    nrm = np.empty((400, d))
    pos, n = deformer.deform(X, out=out, normals_out=nrm)
    assert pos is out and n is nrm and np.array_equal(nrm, expect_n)
    assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)
    # float32 outputs pick the fast kernel
    o32, n32 = np.empty((400, d), np.float32), np.empty((400, d), np.float32)
    deformer.deform(X, out=o32, normals_out=n32)
    assert np.abs(o32 - expect).max() < 1e-5 and np.abs(n32 - expect_n).max() < 1e-4
    # solve, bezier, evaluate, vjp with out=
    solver = mbi.ModifiedBI(U, T)
    M = np.empty((len(U) * d, d))
    assert solver.solve(X, out=M) is M and np.array_equal(M, solver.solve(X))
    B = np.empty((len(T) * (d + 1) * (d + 2) // 2, d))
    assert solver.bezier(X, M, out=B) is B and np.array_equal(B, solver.bezier(X, M))
    pos = np.empty((400, d))
    assert mbi.evaluate(B, deformer.embedding, out=pos) is pos and np.array_equal(pos, expect)
    G = np.ones((400, d))
    g = np.empty((len(U), d))
    assert deformer.vjp(G, out=g) is g and np.array_equal(g, deformer.vjp(G))


def test_out_allocates_no_dense_array(mesh):
    U, T = mesh
    d = U.shape[1]
    p = 20_000 if os.environ.get("MBI_SANITIZED") else 200_000  # ASan is far slower
    deformer = mbi.Deformer(U, T, meshes.points(U, p))
    X = meshes.pose(U)
    out, out32 = np.empty((p, d)), np.empty((p, d), np.float32)
    fast = mbi.FastEvaluator(deformer.embedding)
    B = deformer.bezier(X)
    for call in (lambda: deformer.deform(X, out=out), lambda: deformer.deform(X, out=out32),
                 lambda: fast.evaluate(B, out=out32)):
        call()  # first calls build what is kept (the float kernel's records)
        tracemalloc.start()
        for _ in range(20):
            call()
        current, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        # numpy reports its data allocations to tracemalloc: one dense array would be p d 4 bytes or more
        assert peak < p * d * 4 / 8, peak
    tracemalloc.start()
    deformer.deform(X)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak >= p * d * 8  # the check above sees dense arrays when there are some


def test_normals_follow_the_deformation(mesh):
    U, T = mesh
    d = U.shape[1]
    P = meshes.points(U, 300)
    N = unit_rows(np.random.default_rng(4).standard_normal((300, d)))
    deformer = mbi.Deformer(U, T, P, rest_normals=N)
    assert deformer.has_rest_normals
    R = np.linalg.qr(np.random.default_rng(5).standard_normal((d, d)))[0]
    if np.linalg.det(R) < 0:
        R[:, 0] *= -1
    positions, normals = deformer.deform(U @ R.T + 1.0, normals=True)
    assert np.abs(positions - (P @ R.T + 1.0)).max() < 1e-12
    assert np.abs(normals - N @ R.T).max() < 1e-12  # a rotation rotates the normals
