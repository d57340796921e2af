"""The method's pieces from Python against an independent numpy reference: embedding,
modified-BI's M (reproduction of affine maps, the defining formula), Phong, BI, exact and fast
evaluation, normals, the discontinuity table; arrays of every accepted layout and integer type."""
import numpy as np
import pytest

import mbi
import meshes

METHODS = ["bi", "modified-bi", "phong"]


def test_embed_locates_every_point(mesh):
    U, T = mesh
    P = meshes.points(U, 400)
    emb = mbi.embed(U, T, P)
    d = U.shape[1]
    assert emb.dim == d and emb.size == len(emb) == 400
    assert emb.element.dtype == np.int32 and emb.element.shape == (400,)
    assert emb.bary.shape == (400, d + 1)
    assert np.allclose(emb.bary.sum(1), 1.0, atol=1e-14)
    assert np.abs(mbi.embedded_positions(U, T, emb) - P).max() < 1e-12
    # the points outside the box are the ones reported outside
    lo, hi = U.min(0), U.max(0)
    outside = np.flatnonzero(np.any((P < lo) | (P > hi), axis=1))
    assert set(outside) <= set(emb.outside)
    assert emb.max_outside_distance > 0
    inside = np.setdiff1d(np.arange(400), emb.outside)
    assert emb.bary[inside].min() >= -1e-9
    # the arrays are views of the C++ embedding: read-only
    with pytest.raises(ValueError):
        emb.bary[0, 0] = 1.0


def test_modified_bi_solve_matches_the_defining_formula(mesh):
    U, T = mesh
    d = U.shape[1]
    solver = mbi.ModifiedBI(U, T, alpha=0.15)
    assert (solver.dim, solver.vertices, solver.elements) == (d, len(U), len(T))
    assert solver.alpha == 0.15 and solver.beta > 0
    assert solver.null_space_dim == (6 if d == 3 else 3)
    assert solver.unknowns > 0 and solver.memory_bytes > 0 and solver.factor_nonzeros > 0
    X = meshes.pose(U)
    M = solver.solve(X)
    assert M.shape == (len(U) * d, d)
    emb = mbi.embed(U, T, meshes.points(U, 300))
    B = solver.bezier(X, M)
    assert B.shape == (len(T) * (d + 1) * (d + 2) // 2, d)
    expect = meshes.reference(U, T, X, M, emb)
    assert np.abs(mbi.evaluate(B, emb) - expect).max() < 1e-12 * (1 + np.abs(expect).max())
    assert np.abs(mbi.bezier_points(U, T, X, M) - B).max() == 0.0


@pytest.mark.parametrize("layout", ["C", "F", "rows apart"])
def test_out_is_written_where_it_is_and_equals_the_new_result(mesh, layout):
    """solve, Phong.M and bezier with out= write into the caller's array itself (C order, Fortran
    order, every other row of a larger one) the same bits as the calls that return a new array."""
    U, T = mesh
    X = meshes.pose(U)
    solver, phong = mbi.ModifiedBI(U, T), mbi.Phong(U, T)
    M = solver.solve(X)
    for call, expect in ((lambda o: solver.solve(X, out=o), M), (lambda o: phong.M(X, out=o), phong.M(X)),
                         (lambda o: solver.bezier(X, M, out=o), solver.bezier(X, M))):
        if layout == "rows apart":
            out = np.full((2 * expect.shape[0], expect.shape[1]), np.nan)[::2]
        else:
            out = np.full(expect.shape, np.nan, order=layout)
        assert call(out) is out
        assert np.array_equal(out, expect)


def test_every_method_reproduces_affine_maps(mesh):
    U, T = mesh
    d = U.shape[1]
    A = np.eye(d) + 0.3 * np.arange(d * d).reshape(d, d) / (d * d)
    X = U @ A.T + 0.5
    P = meshes.points(U, 200)
    for method in METHODS:
        deformer = mbi.Deformer(U, T, P, method=method)
        assert np.abs(deformer.deform(X) - (P @ A.T + 0.5)).max() < 1e-12, method
    # BI is exact there, so modified-BI's M is 0 (E_total = 0, the gauge pinned); Phong's is A / 2
    assert np.abs(mbi.ModifiedBI(U, T).solve(X)).max() < 1e-12
    assert np.abs(mbi.Phong(U, T).M(X).reshape(-1, d, d) - A / 2).max() < 1e-12


def test_bi_is_the_linear_interpolant(mesh):
    U, T = mesh
    X = meshes.pose(U)
    emb = mbi.embed(U, T, meshes.points(U, 300))
    linear = np.einsum("pk,pkc->pc", emb.bary, X[T[emb.element]])
    assert np.abs(mbi.evaluate(mbi.bezier_bi(X, T), emb) - linear).max() < 1e-12


def test_phong_gradients(mesh):
    U, T = mesh
    d = U.shape[1]
    phong = mbi.Phong(U, T)
    X = meshes.pose(U)
    Fe = phong.element_gradients(X).reshape(-1, d, d)
    # F_e maps the rest edges to the deformed ones
    Ds = (X[T[:, 1:]] - X[T[:, :1]]).transpose(0, 2, 1)
    Dm = (U[T[:, 1:]] - U[T[:, :1]]).transpose(0, 2, 1)
    assert np.abs(Fe @ Dm - Ds).max() < 1e-12
    assert np.abs(phong.M(X) - phong.vertex_gradients(X) / 2).max() < 1e-15
    assert phong.fallback_vertices == 0


def test_fast_evaluator_agrees_with_the_exact_path(mesh):
    U, T = mesh
    d = U.shape[1]
    P = meshes.points(U, 2000)
    emb = mbi.embed(U, T, P)
    solver = mbi.ModifiedBI(U, T)
    X = meshes.pose(U)
    B = solver.bezier(X, solver.solve(X))
    rng = np.random.default_rng(1)
    N = rng.standard_normal((2000, d))
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    exact, normals = mbi.evaluate(B, emb, rest_normals=N)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    fast = mbi.FastEvaluator(emb, threads=2)
    assert fast.size == 2000 and fast.dim == d and fast.simd in ("avx512", "avx2", "portable")
    assert fast.bytes_per_point() == 4 * (d + 1) + 4 * d
    pos = fast.evaluate(B)
    assert pos.dtype == np.float32 and pos.shape == (2000, d) and pos.flags.c_contiguous
    assert np.abs(pos - exact).max() < 1e-5
    fast.set_rest_normals(N)
    pos, nrm = fast.evaluate(B, normals=True)
    assert np.abs(nrm - normals).max() < 1e-4
    # a Bezier array in C order is read through a copy: the same result
    assert np.array_equal(fast.evaluate(np.ascontiguousarray(B)), pos)
    assert mbi.FastEvaluator.supported("portable")
    assert not fast.sorted_by_element  # a small mesh: the points keep their order


def test_fast_evaluator_sorts_random_points_over_a_large_mesh_and_gives_each_its_row():
    U, T = mbi.box_mesh(30, 30, 30)  # 162,000 tetrahedra: their terms exceed 16 MiB
    rng = np.random.default_rng(5)
    P = rng.uniform(0.0, 1.0, (20000, 3))
    emb = mbi.embed(U, T, P)
    B = mbi.bezier_bi(U + 0.05 * np.sin(4 * U), T)
    fast = mbi.FastEvaluator(emb, threads=2)
    assert fast.sorted_by_element
    order = np.argsort(emb.element, kind="stable")
    in_order = mbi.FastEvaluator(mbi.embed(U, T, P[order]), threads=2)
    assert not in_order.sorted_by_element
    # each point's row, to the bit, whatever the order the points come in
    assert np.array_equal(fast.evaluate(B)[order], in_order.evaluate(B))
    assert np.abs(fast.evaluate(B) - mbi.evaluate(B, emb)).max() < 1e-5


def test_discontinuity_table(mesh):
    U, T = mesh
    solver = mbi.ModifiedBI(U, T)
    X = meshes.pose(U)
    M = solver.solve(X)
    table = mbi.discontinuity_table(solver, X, M)
    faces = mbi.interior_faces(T)
    assert table.faces == len(faces)
    assert table.phong is None
    assert table.bi.mean > table.modified_bi.mean > 0
    assert table.ratio.mean == pytest.approx(table.bi.mean / table.modified_bi.mean)
    per_face = mbi.face_discontinuity(U, T, X, M)
    assert per_face.shape == (len(faces),)
    assert per_face.mean() == pytest.approx(table.modified_bi.mean)
    assert per_face.max() == pytest.approx(table.modified_bi.max)
    assert table.e_disc == pytest.approx(per_face.sum())
    with_phong = mbi.discontinuity_table(solver, X, M, mbi.Phong(U, T).M(X))
    assert table.bi.mean > with_phong.phong.mean > table.modified_bi.mean
    assert mbi.boundary_faces(U, T).shape[1] == U.shape[1]


def test_layouts_and_integer_types_give_the_same_results(mesh):
    U, T = mesh
    P = meshes.points(U, 100)
    X = meshes.pose(U)
    expect = mbi.Deformer(U, T, P).deform(X)
    variants = [
        (np.asfortranarray(U), T.astype(np.int32), np.asfortranarray(P), np.asfortranarray(X)),
        (U, T.astype(np.uint16), P, X),
        (U, T.astype(np.int8), P.tolist(), X.tolist()),
        (U, T.astype(np.uint64), P, X[::-1][::-1]),
    ]
    for u, t, p, x in variants:
        assert np.array_equal(mbi.Deformer(u, t, p).deform(x), expect)
    # a strided view (every other row of a larger array) is read in place
    big = np.zeros((2 * len(X), U.shape[1] + 1))
    big[::2, :-1] = X
    assert np.array_equal(mbi.Deformer(U, T, P).deform(big[::2, :-1]), expect)
    # float32 inputs are converted (exactly) to float64
    x32 = X.astype(np.float32)
    assert np.array_equal(mbi.Deformer(U, T, P).deform(x32), mbi.Deformer(U, T, P).deform(x32.astype(np.float64)))


def test_set_alpha_refactors(mesh):
    U, T = mesh
    X = meshes.pose(U)
    a, b = mbi.ModifiedBI(U, T, alpha=0.1), mbi.ModifiedBI(U, T, alpha=0.3)
    a.set_alpha(0.3)
    assert a.alpha == 0.3
    assert np.abs(a.solve(X) - b.solve(X)).max() < 1e-10
    assert mbi.default_alpha(U.shape[1]) == (0.1 if U.shape[1] == 3 else 0.2)


def test_solve_paths_and_factorizations_agree(mesh):
    U, T = mesh
    X = meshes.pose(U)
    expect = mbi.ModifiedBI(U, T, solve_path="sparse", factorization="eigen").solve(X)
    factorizations = ["eigen"] + (["cholmod"] if mbi.cholmod_available() else [])
    for path in ("dense", "automatic"):
        for fac in factorizations:
            got = mbi.ModifiedBI(U, T, solve_path=path, factorization=fac).solve(X)
            assert np.abs(got - expect).max() < 1e-9 * (1 + np.abs(expect).max())
    pinned = mbi.ModifiedBI(U, T, pin_boundary=True)
    assert pinned.pin_boundary and pinned.null_space_dim == 0



def test_iterative_path_is_within_1e_6_of_the_model_size_of_the_factor(mesh):
    U, T = mesh
    X = meshes.pose(U)
    embedding = mbi.embed(U, T, U[T].mean(axis=1))  # element centroids: inside the control mesh
    size = np.linalg.norm(X.max(axis=0) - X.min(axis=0))
    direct, iterative = (mbi.ModifiedBI(U, T, solve_path=p) for p in ("sparse", "iterative"))
    at = [mbi.evaluate(s.bezier(X, s.solve(X)), embedding) for s in (direct, iterative)]
    assert 0 < np.abs(at[1] - at[0]).max() <= 1e-6 * size

def test_box_mesh_fills_its_box_with_positive_tetrahedra():
    U, T = mbi.box_mesh(3, 2, 4, (3.0, 1.0, 2.0))
    assert U.shape == (4 * 3 * 5, 3) and T.shape == (6 * 3 * 2 * 4, 4) and T.dtype == np.int32
    volumes = np.linalg.det(U[T[:, 1:]] - U[T[:, :1]]) / 6
    assert (volumes > 0).all()
    assert abs(volumes.sum() - 6.0) < 1e-12  # the box's volume, 3 x 1 x 2
    mbi.validate_mesh(U, T)
    with pytest.raises(ValueError, match="at least one cell"):
        mbi.box_mesh(0, 1, 1)


def test_harmonic_extension_against_a_dense_dirichlet_solve(mesh):
    U, T = mesh
    d = U.shape[1]
    h = mbi.HarmonicExtension(U, T)  # fixed: the boundary's nodes
    boundary = np.unique(mbi.boundary_faces(U, T))
    assert np.array_equal(h.fixed_nodes, boundary) and h.free_nodes.dtype == np.int32
    free = np.setdiff1d(np.arange(len(U)), boundary)
    assert np.array_equal(h.free_nodes, free) and len(free) > 0
    K = np.zeros((len(U), len(U)))  # P1 stiffness from numpy's own element gradients
    for t in T:
        E = (U[t[1:]] - U[t[0]]).T
        G = np.vstack([-np.linalg.inv(E).sum(0), np.linalg.inv(E)])
        K[np.ix_(t, t)] += abs(np.linalg.det(E)) / np.prod(np.arange(1, d + 1)) * G @ G.T
    X = meshes.pose(U)
    X_before = X.copy()
    D = X - U
    D[free] = np.linalg.solve(K[np.ix_(free, free)], -K[np.ix_(free, boundary)] @ D[boundary])
    assert np.abs(h.apply(X) - (U + D)).max() < 1e-12
    assert np.array_equal(X, X_before)  # the input is not modified
    mask = np.zeros(len(U), dtype=bool)
    mask[boundary] = True
    assert np.abs(mbi.HarmonicExtension(U, T, fixed=mask).apply(X) - (U + D)).max() < 1e-12


def test_harmonic_extension_refuses_bad_fixed_sets(mesh):
    U, T = mesh
    with pytest.raises(mbi.Error, match="given twice"):
        mbi.HarmonicExtension(U, T, fixed=[0, 0])
    with pytest.raises(mbi.Error, match="fixed"):
        mbi.HarmonicExtension(U, T, fixed=[len(U)])
    with pytest.raises(mbi.Error, match="row per node"):
        mbi.HarmonicExtension(U, T).apply(U[:2])
