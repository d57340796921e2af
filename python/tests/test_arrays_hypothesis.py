"""Property tests of the array intake (python3-hypothesis): every entry point that takes or fills
an array gives, for arrays drawn in any layout (C, Fortran, strided, reversed, transposed,
unaligned, frames apart, zero strides, overlapping rows), dtype (float16/32/64, long double,
both byte orders; signed and unsigned indices) and flags (read-only), the same outcome as the
same call on contiguous copies: equal results, or the same mbi.Error. out= arrays drawn the
same way are written in place (the call returns them) with the results of out=None.
Derandomized and bounded, so that CI runs the same examples every time, in seconds."""
import os
import tempfile

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import layouts
import mbi
import meshes
from layouts import arrange, contiguous

settings.register_profile("mbi", max_examples=60, deadline=None, derandomize=True, database=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile("mbi")

U, T = mbi.box_mesh(2, 1, 1, size=(2.0, 1.0, 1.0))
U = U + 0.03 * np.random.default_rng(1).standard_normal(U.shape)
P = meshes.points(U, 16)
N = np.tile([0.0, 0.6, 0.8], (16, 1))
X = meshes.pose(U)
n, p = len(U), len(P)
DEFORMER = mbi.Deformer(U, T, P, rest_normals=N)
SOLVER = mbi.ModifiedBI(U, T)
PHONG = mbi.Phong(U, T)
EMBEDDING = DEFORMER.embedding
B = DEFORMER.bezier(X)

# (layout, dtype, read-only) of a float input, an index input, and an out= (or None)
float_input = st.tuples(st.sampled_from(layouts.LAYOUTS), st.sampled_from(layouts.FLOATS), st.booleans())
index_input = st.tuples(st.sampled_from(layouts.LAYOUTS), st.sampled_from(layouts.INTEGERS), st.booleans())
out64 = st.one_of(st.none(), st.tuples(st.sampled_from(layouts.WRITABLE), st.sampled_from(["<f8", ">f8"])))
out32 = st.one_of(st.none(), st.tuples(st.sampled_from(layouts.WRITABLE), st.sampled_from(["<f4", ">f4"])))
frames = st.sampled_from([None, 0, 1, 3])  # None: one (n, d) pose; else a batch


def outcome(call):
    try:
        return "ok", call()
    except mbi.Error as e:
        return "error", str(e)


def assert_same(got, want):
    """Equal outcomes: both raised the same message, or both gave equal results."""
    assert got[0] == want[0], (got, want)
    if got[0] == "error":
        assert got[1] == want[1]
        return
    a, b = got[1], want[1]
    if isinstance(b, tuple):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            assert_same(("ok", x), ("ok", y))
    elif isinstance(b, mbi.Embedding):
        assert np.array_equal(a.element, b.element)
        np.testing.assert_allclose(a.bary, b.bary, rtol=1e-12, atol=1e-12)
    else:
        a, b = np.asarray(a), np.asarray(b)
        assert a.shape == b.shape and a.dtype.kind == b.dtype.kind
        if a.dtype.kind in "biu":
            assert np.array_equal(a, b)
            return
        tol = 1e-5 if a.dtype.itemsize == 4 else 1e-11
        np.testing.assert_allclose(a, b, rtol=tol, atol=tol)


def compare(call, *arrays):
    """call(*arrays) against call(*contiguous copies)."""
    assert_same(outcome(lambda: call(*arrays)), outcome(lambda: call(*[contiguous(a) for a in arrays])))


def make_out(spec, shape):
    """None, or an out= array of `shape` in the drawn (layout, dtype), filled with NaN."""
    if spec is None:
        return None
    out = arrange(np.full(shape, np.nan), spec[0], spec[1])
    assert out.flags.writeable
    return out


def written_in_place(result, out, expect):
    """The call returned out= itself, holding the results of the call without it."""
    first = result[0] if isinstance(result, tuple) else result
    assert first is out
    assert_same(("ok", np.array(out)), ("ok", expect))


def poses(count):
    if count is None:
        return X
    return np.array([meshes.pose(U, seed=s) for s in range(count)]).reshape(count, n, 3)


@given(float_input, index_input, float_input)
def test_embed(u, t, q):
    compare(mbi.embed, arrange(U, *u), arrange(T, *t), arrange(P, *q))


@given(float_input, out64)
def test_evaluate(b, out):
    view = arrange(B, *b)
    expect = mbi.evaluate(contiguous(view), EMBEDDING)
    target = make_out(out, (p, 3))
    result = mbi.evaluate(view, EMBEDDING, out=target)
    if target is None:
        assert_same(("ok", result), ("ok", expect))
    else:
        written_in_place(result, target, expect)


@given(float_input, out32, st.booleans())
def test_fast_evaluator(b, out, normals):
    fast = mbi.FastEvaluator(EMBEDDING, threads=1)
    fast.set_rest_normals(N)
    view = arrange(B, *b)
    expect = fast.evaluate(contiguous(view), normals=normals)
    target = make_out(out, (p, 3))
    result = fast.evaluate(view, out=target, normals=normals)
    if target is None:
        assert_same(("ok", result), ("ok", expect))
    else:
        written_in_place(result, target, expect[0] if normals else expect)


@given(float_input, float_input, out64)
def test_modified_bi_and_phong(x, m, out):
    xv = arrange(X, *x)
    compare(SOLVER.solve, xv)
    M = SOLVER.solve(contiguous(xv))
    compare(SOLVER.bezier, xv, arrange(M, *m))
    compare(PHONG.M, xv)
    compare(PHONG.M_transpose, arrange(M, *m))
    compare(SOLVER.solve_transpose, arrange(M, *m))
    target = make_out(out, M.shape)
    if target is not None:
        written_in_place(SOLVER.solve(xv, out=target), target, M)
        target[...] = np.nan
        written_in_place(PHONG.M(xv, out=target), target, PHONG.M(contiguous(xv)))


@given(float_input, frames, st.one_of(out64, out32), st.booleans(), st.booleans())
def test_deformer_deform(x, count, out, normals, single):
    view = arrange(poses(count), *x)
    shape = (p, 3) if count is None else (count, p, 3)
    dtype = np.float32 if (out[1].endswith("4") if out else single) else np.float64
    expect = DEFORMER.deform(contiguous(view), normals=normals, dtype=dtype)
    target = make_out(out, shape)
    normals_out = make_out(out, shape) if normals else None
    result = DEFORMER.deform(view, out=target, normals=normals, normals_out=normals_out, dtype=dtype)
    if target is None:
        assert_same(("ok", result), ("ok", expect))
        return
    written_in_place(result, target, expect[0] if normals else expect)
    if normals:
        assert result[1] is normals_out
        assert_same(("ok", np.array(normals_out)), ("ok", expect[1]))


@given(float_input, frames, out64)
def test_deformer_vjp(g, count, out):
    G = np.random.default_rng(3).standard_normal((p, 3) if count is None else (count, p, 3))
    view = arrange(G, *g)
    expect = DEFORMER.vjp(contiguous(view))
    target = make_out(out, expect.shape)
    result = DEFORMER.vjp(view, out=target)
    if target is None:
        assert_same(("ok", result), ("ok", expect))
    else:
        written_in_place(result, target, expect)
    G2 = np.random.default_rng(4).standard_normal((p, 3))
    compare(lambda A: mbi.evaluate_transpose(EMBEDDING, A, len(T)), arrange(G2, *g))


VECTOR_FORMS = ["list", "tuple", "C", "reversed", "steps", "broadcast", "float32", "int"]


def vector(values, form):
    """A 3- or 4-vector as the drawn kind of argument (for broadcast: all entries the first)."""
    v = np.asarray(values, dtype=np.float64)
    if form == "list":
        return list(v)
    if form == "tuple":
        return tuple(v)
    if form == "reversed":
        return v[::-1].copy()[::-1]
    if form == "steps":
        big = np.zeros(2 * len(v))
        big[::2] = v
        return big[::2]
    if form == "broadcast":
        return np.broadcast_to(v[0], v.shape)
    if form == "float32":
        return v.astype(np.float32)
    if form == "int":
        return np.round(v).astype(np.int64)
    return v


def stepped(sim, steps=2):
    """Whether each step succeeded, and the positions after them."""
    return np.array([sim.step().success for _ in range(steps)]), sim.positions


@settings(max_examples=30)
@given(float_input, float_input, st.sampled_from(VECTOR_FORMS), st.sampled_from(VECTOR_FORMS), float_input)
def test_simulator_setters(x, v, gform, fform, materials):
    def run(positions, velocities, gravity, force, element_materials):
        sim = mbi.Simulator(U, T, element_materials=element_materials, dt=0.01, gravity=gravity)
        sim.set_positions(positions)
        sim.set_velocities(velocities)
        sim.add_point_force(3, vector([0.25] * 4, fform), force)
        sim.fix([0, 1])
        return stepped(sim)

    velocities = 0.1 * np.random.default_rng(4).standard_normal(U.shape)
    mats = np.tile([1e5, 0.3, 1000.0], (len(T), 1))
    mats[:, 0] *= np.linspace(1, 2, len(T))
    args = [arrange(U + 0.01, *x), arrange(velocities, *v), vector([0.0, -9.81, 0.5], gform),
            vector([1.0, 2.0, 3.0], fform), arrange(mats, *materials)]
    got = outcome(lambda: run(*args))
    want = outcome(lambda: run(*[contiguous(np.asarray(a, dtype=float)) for a in args]))
    assert_same(got, want)


@settings(max_examples=30)
@given(float_input, index_input, float_input, st.sampled_from([1, 3]))
def test_file_writers(u, t, q, count):
    traj = arrange(np.stack([meshes.pose(U, seed=s) for s in range(count)]), q[0], q[1])
    with tempfile.TemporaryDirectory() as folder:
        def written(name, write, *arrays):
            path = os.path.join(folder, name)
            result = outcome(lambda: write(path, *arrays))
            data = None
            if result[0] == "ok":
                with open(path, "rb") as f:
                    data = f.read()
                os.remove(path)
            return result[0], result[1] if result[0] == "error" else data

        cases = [("p.xyz", mbi.write_points, arrange(P, *q)),
                 ("u.vtk", mbi.write_vtk, arrange(U, *u), arrange(T, *t), arrange(X - U, *q)),
                 ("c.pc2", mbi.write_point_cache, traj),
                 ("c.mdd", mbi.write_point_cache, traj),
                 ("s.obj", mbi.write_surface, arrange(U, *u), arrange(mbi.boundary_faces(U, T), *t)),
                 ("s.ply", lambda path, V, F: mbi.write_surface(path, mbi.Surface(V, F), encoding="binary"),
                  arrange(U, *u), arrange(mbi.boundary_faces(U, T), *t))]
        for name, write, *arrays in cases:
            got = written(name, write, *arrays)
            want = written(name, write, *[contiguous(a) for a in arrays])
            assert got == want, name


@settings(max_examples=20)
@given(float_input, st.sampled_from([1, 3]), float_input)
def test_pipeline_drivers(x, count, targets):
    compare(lambda Xs: mbi.FramePipeline(U, T, P, mbi.GivenDriver(Xs), method="bi").run(count),
            arrange(poses(count), *x))

    def dragged(t):
        driver = mbi.HandleDriver(U, T, [0, 5, 11])
        pipe = mbi.FramePipeline(U, T, P, driver)
        pipe.step()
        driver.set_targets(t)
        pipe.step()
        return pipe.positions

    compare(dragged, arrange(U[[0, 5, 11]] + 0.1, *targets))
