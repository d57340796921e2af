"""Every refused input raises mbi.Error (a ValueError) with the library's message, never a crash:
wrong shapes, dtypes, NaN, out-of-range indices, bad out= arrays, unknown names, bad options."""
import numpy as np
import pytest

import mbi
import meshes


@pytest.fixture
def setup():
    U, T = meshes.jittered(3)
    P = meshes.points(U, 50)
    return U, T, P, mbi.Deformer(U, T, P)


def raises(match):
    return pytest.raises(mbi.Error, match=match)


def test_error_is_a_value_error():
    assert issubclass(mbi.Error, ValueError)


def test_shapes(setup):
    U, T, P, deformer = setup
    with raises(r"U must be a 2D array"):
        mbi.embed(U.ravel(), T, P)
    with raises(r"T must have shape \(m, 4\), got \(96, 3\)"):
        mbi.embed(U, T[:, :3], P)
    with raises(r"P must have shape \(n, 3\)|P must have shape"):
        mbi.embed(U, T, P[:, :2])
    with raises(r"X must have shape \(45, 3\), got \(44, 3\)"):
        deformer.deform(U[:-1])
    with raises(r"X must be"):
        deformer.deform(np.zeros((2, 2, 45, 3)))
    with raises(r"X must have shape \(frames, 45, 3\)"):
        deformer.deform(np.zeros((2, 44, 3)))
    with raises(r"G must have shape \(50, 3\)"):
        deformer.vjp(np.zeros((49, 3)))
    with raises(r"M must have shape"):
        mbi.ModifiedBI(U, T).bezier(U, np.zeros((3, 3)))
    with raises(r"B must have shape"):
        mbi.evaluate(np.zeros((10, 2)), deformer.embedding)
    with raises(r"Bezier points have 11 rows"):
        mbi.evaluate(np.zeros((11, 3)), deformer.embedding)
    with raises(r"rest_normals must have shape"):
        mbi.Deformer(U, T, P, rest_normals=np.ones((3, 3)))
    with raises(r"must be n x 2 or n x 3, got 5 x 4"):
        mbi.embed(np.zeros((5, 4)), np.zeros((1, 5), int), np.zeros((1, 4)))


def test_dtypes(setup):
    U, T, P, deformer = setup
    with raises(r"T must be an integer array, got dtype float64"):
        mbi.embed(U, T.astype(float), P)
    with raises(r"T must be an integer array, got dtype bool"):
        mbi.embed(U, T.astype(bool), P)
    with raises(r"U must be a float array \(float64; integers are taken too\), got dtype bool"):
        mbi.embed(U.astype(bool), T, P)
    with raises(r"X must be a float array \(float64; integers are taken too\), got dtype complex128"):
        deformer.deform(U.astype(complex))
    with raises(r"X must be a float array"):
        deformer.deform(np.array([["a", "b", "c"]] * 45))
    with raises(r"X must be \(45, 3\) or a batch \(frames, 45, 3\), got shape \(\)"):
        deformer.deform(object())
    with raises(r"X is missing"):
        deformer.deform(None)
    with raises(r"dtype must be float64 \(exact\) or float32"):
        deformer.deform(U, dtype=np.float16)
    with raises(r"dtype:"):
        deformer.deform(U, dtype="no such type")


def test_non_finite_values(setup):
    U, T, P, deformer = setup
    for bad in (np.nan, np.inf, -np.inf):
        X = U.copy()
        X[7, 2] = bad
        with raises(r"X\[7, 2\] is not finite"):
            deformer.deform(X)
        with raises(r"X\[7, 2\] is not finite"):
            mbi.ModifiedBI(U, T).solve(X)
        Ub = U.copy()
        Ub[3, 0] = bad
        with raises(r"U\[3, 0\] is not finite"):
            mbi.Deformer(Ub, T, P)
        Pb = P.copy()
        Pb[5, 1] = bad
        with raises(r"P\[5, 1\] is not finite"):
            mbi.embed(U, T, Pb)
        G = np.zeros((50, 3))
        G[9, 0] = bad
        with raises(r"dL/dpositions row 9 has a non-finite value"):
            deformer.vjp(G)
        B = deformer.bezier(U)
        B[0, 0] = bad
        with raises(r"B\[0, 0\] is not finite"):
            mbi.evaluate(B, deformer.embedding)
        M = np.zeros((45 * 3, 3))
        M[4, 1] = bad
        with raises(r"G\[4, 1\] is not finite"):
            mbi.ModifiedBI(U, T).solve_transpose(M)


def test_indices_out_of_range(setup):
    U, T, P, _ = setup
    for value, match in ((45, r"outside|index|range"), (-1, r"outside|index|range|negative"),
                         (2**31, r"is out of range \(indices fit in 32 bits\)"),
                         (-2**40, r"is out of range \(indices fit in 32 bits\)")):
        Tb = T.astype(np.int64)
        Tb[3, 1] = value
        with raises(match):
            mbi.Deformer(U, Tb, P)
    Tb = T.astype(np.uint64)
    Tb[0, 0] = 2**63
    with raises(r"T\[0, 0\] = 9223372036854775808 is out of range"):
        mbi.ModifiedBI(U, Tb)
    Tb = T.copy()
    Tb[2, 3] = Tb[2, 0]
    with raises(r"element 2"):
        mbi.Phong(U, Tb)


def test_bad_out_arrays(setup):
    U, T, P, deformer = setup
    with raises(r"out must have shape \(50, 3\), got \(50, 2\)"):
        deformer.deform(U, out=np.empty((50, 2)))
    with raises(r"out must be a float64 array"):
        mbi.evaluate(deformer.bezier(U), deformer.embedding, out=np.empty((50, 3), np.int64))
    with raises(r"out must be a numpy array"):
        deformer.deform(U, out=[[0.0] * 3] * 50)
    read_only = np.empty((50, 3))
    read_only.flags.writeable = False
    with raises(r"out is read-only"):
        deformer.deform(U, out=read_only)
    with raises(r"out overlaps itself"):
        deformer.deform(U, out=np.lib.stride_tricks.as_strided(np.zeros(3, np.float32), (50, 3), (0, 4)))
    with raises(r"out must be a float32 array"):
        mbi.FastEvaluator(deformer.embedding).evaluate(deformer.bezier(U), out=np.empty((50, 3)))
    with raises(r"out must have shape \(2, 50, 3\)"):
        deformer.deform(np.stack([U, U]), out=np.empty((100, 3)))
    positions = np.empty((50, 3))
    with raises(r"out shares memory with normals_out"):
        mbi.Deformer(U, T, P, rest_normals=np.tile([1.0, 0, 0], (50, 1))).deform(U, out=positions, normals_out=positions)
    with raises(r"out must be a float64 array|got dtype"):
        deformer.vjp(np.zeros((50, 3)), out=np.empty((45, 3), np.float32))


def test_options_and_names(setup):
    U, T, P, deformer = setup
    with raises(r'method: unknown value "mbi" \(expected one of: bi, modified-bi, phong\)'):
        mbi.Deformer(U, T, P, method="mbi")
    with raises(r"solve_path: unknown value"):
        mbi.ModifiedBI(U, T, solve_path="fast")
    with raises(r"factorization: unknown value"):
        mbi.ModifiedBI(U, T, factorization="lu")
    with raises(r"simd: unknown value"):
        mbi.FastEvaluator(deformer.embedding, simd="neon")
    with raises(r"alpha must be"):
        mbi.ModifiedBI(U, T, alpha=-1.0)
    with raises(r"beta must be"):
        mbi.ModifiedBI(U, T, beta=float("nan"))
    with raises(r"alpha must be"):
        deformer.set_alpha(0.0)
    with raises(r"threads must be a whole number from 0"):
        mbi.Deformer(U, T, P, threads=-2)
    bi = mbi.Deformer(U, T, P, method="bi")
    with raises(r"alpha is a parameter of modified-BI, not of bi"):
        bi.set_alpha(0.2)
    with raises(r"no rest normals"):
        bi.deform(U, normals=True)
    with raises(r"no rest normals"):
        bi.deform(U, normals=True, dtype=np.float32)
    with raises(r"normals asked for, but no rest normals were set"):
        mbi.FastEvaluator(deformer.embedding).evaluate(deformer.bezier(U), normals=True)
    with raises(r"normals_out needs rest_normals"):
        mbi.evaluate(deformer.bezier(U), deformer.embedding, normals_out=np.empty((50, 3)))
    if mbi._mbi._timing is not None:  # a module built with MBI_PYTHON_TIMING
        with raises(r"calls must be >= 1"):
            mbi._mbi._timing.solve(mbi.ModifiedBI(U, T), U, 0)


def test_mesh_errors():
    U, T = meshes.box(1, 1, 1)
    flat = U.copy()
    flat[:, 2] = 0
    with raises(r"degenerate|flat|volume"):
        mbi.ModifiedBI(flat, T)
    with raises(r"interior faces|single element"):
        mbi.ModifiedBI(U, T[:1])
    with raises(r"farther than|far"):
        mbi.embed(U, T, np.array([[1e20, 0.0, 0.0]]))
    with raises(r"2D or 3D|2 or 3"):
        mbi.default_alpha(4)


def test_non_finite_anywhere_in_any_layout(setup):
    """The finite check reads C and Fortran order at once and strided arrays value by value: each
    finds a bad value at the first, a middle and the last place, and names it."""
    U, T, P, deformer = setup
    n = len(U)
    for bad in (np.nan, np.inf, -np.inf, -np.nan):
        for i, c in ((0, 0), (n // 2, 1), (n - 1, 2)):
            X = U.copy()
            X[i, c] = bad
            wide = np.zeros((n, 6))
            wide[:, ::2] = X
            for layout in (X, np.asfortranarray(X), wide[:, ::2]):
                with raises(rf"X\[{i}, {c}\] is not finite"):
                    deformer.deform(layout)
    huge = U.copy()
    huge[3, 1] = np.finfo(np.float64).max  # the largest finite value passes
    deformer.deform(huge)
