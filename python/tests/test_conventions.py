"""One convention for every function (docs/python.md, "Conventions"): float64 (n, 3) arrays in,
integer positions taken where floats are; int32 indices out everywhere; every pair or triple
result unpacks; boolean masks wherever node sets are taken; dL/dX in C order like X, M and B in
Fortran order; the Python keyword names and the docs' row letters in messages; one-line
TypeErrors naming the argument instead of pybind11's overload list; tensors that require grad
refused in one line; mbi.torch taking numpy arrays."""
import numpy as np
import pytest

import mbi


@pytest.fixture
def bar():
    U, T = mbi.box_mesh(1, 1, 3, size=(1.0, 1.0, 3.0))
    P = np.random.default_rng(3).uniform(0.05, 0.95, (30, 3)) * (1.0, 1.0, 3.0)
    return U, T, P


def test_every_index_array_out_is_int32(bar, tmp_path):
    U, T, P = bar
    assert T.dtype == np.int32
    embedding = mbi.embed(U, T, P)
    path = tmp_path / "s.obj"
    mbi.write_surface(path, U, mbi.boundary_faces(U, T))
    mbi.write_tetgen(tmp_path / "c", U, T)
    for indices in (embedding.element, embedding.outside, mbi.interior_faces(T), mbi.boundary_faces(U, T),
                    mbi.read_surface(path).F, mbi.read_control_mesh(tmp_path / "c.node").T,
                    mbi.cage(U * 4, vertices=20).T):
        assert indices.dtype == np.int32


def test_pairs_and_triples_unpack(bar, tmp_path):
    U, T, P = bar
    path = tmp_path / "s.obj"
    mbi.write_surface(path, U, mbi.boundary_faces(U, T))
    V, F = mbi.read_surface(path)
    assert np.array_equal(V, U) and F.shape[1] == 3
    V2, F2 = mbi.Surface(U, F)
    assert np.array_equal(F2, F)
    mbi.write_tetgen(tmp_path / "c", U, T)
    U2, T2 = mbi.read_control_mesh(tmp_path / "c.node")
    CU, CT = mbi.cage(U * 4, vertices=20)
    dX, dM = mbi.bezier_transpose(U, T, np.ones((len(T) * 10, 3)))
    mbi.write_point_cache(tmp_path / "c.pc2", np.stack([U, U]))
    X, times = mbi.read_trajectory(tmp_path / "c.pc2")
    deformer = mbi.Deformer(U, T, P, rest_normals=np.tile([0.0, 0.0, 1.0], (30, 1)))
    positions, normals = deformer.deform(U, normals=True)
    positions2, normals2 = mbi.evaluate(deformer.bezier(U), deformer.embedding,
                                        rest_normals=np.tile([0.0, 0.0, 1.0], (30, 1)))
    assert np.array_equal(T2, T) and X.shape == (2, len(U), 3) and np.allclose(positions, positions2)


def test_integer_positions_are_taken_where_floats_are(bar, tmp_path):
    U, T, P = bar
    integer = np.rint(U * 2).astype(np.int64)  # a grid of integers, exact in float64
    deformer = mbi.Deformer(integer, T, P * 2)
    assert np.array_equal(deformer.deform(integer), mbi.Deformer(integer.astype(float), T, P * 2).deform(U * 2))
    path = tmp_path / "tri.obj"
    mbi.write_surface(path, [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])  # plain lists of ints
    assert mbi.read_surface(path).V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    sim = mbi.Simulator(U, T, gravity=(0, -10, 0))
    sim.set_positions(np.rint(U).astype(np.int32))
    assert np.array_equal(sim.positions, np.rint(U))


def test_boolean_masks_are_node_sets(bar):
    U, T, _ = bar
    clamped = U[:, 2] == 0
    by_mask, by_index = (mbi.Simulator(U, T, dt=0.02) for _ in range(2))
    by_mask.fix(clamped)
    by_index.fix(np.flatnonzero(clamped))
    by_mask.add_kinematic(U[:, 2] == 3, velocity=(0.1, 0, 0))
    by_index.add_kinematic(np.flatnonzero(U[:, 2] == 3), velocity=(0.1, 0, 0))
    for _ in range(3):
        by_mask.step(), by_index.step()
    assert np.array_equal(by_mask.positions, by_index.positions)
    assert np.array_equal(by_mask.positions[clamped], U[clamped])
    driver = mbi.HandleDriver(U, T, U[:, 2] == 0)
    assert driver.handles == np.flatnonzero(clamped).tolist()
    with pytest.raises(mbi.Error, match=r"^nodes is a boolean mask of 3 entries; it needs 16, one a node$"):
        by_mask.fix(clamped[:3])


def test_layouts_of_results(bar):
    U, T, P = bar
    deformer = mbi.Deformer(U, T, P)
    G = np.ones((30, 3))
    assert deformer.deform(U).flags.c_contiguous and deformer.vjp(G).flags.c_contiguous  # like X and P
    solver, phong = mbi.ModifiedBI(U, T), mbi.Phong(U, T)
    M = solver.solve(U)
    assert M.flags.f_contiguous and solver.bezier(U, M).flags.f_contiguous  # handed over, no copy
    assert solver.solve_transpose(M).flags.c_contiguous and phong.M_transpose(M).flags.c_contiguous
    assert mbi.bezier_transpose(U, T, np.ones((len(T) * 10, 3)))[0].flags.c_contiguous
    assert deformer.vjp(np.stack([G, G])).flags.c_contiguous


def test_messages_use_the_keyword_names_and_the_docs_letters(bar):
    U, T, P = bar
    with pytest.raises(mbi.Error, match=r"^vertices 3 out of range \[8, 1000000\]$"):
        mbi.cage(U, vertices=3)
    with pytest.raises(mbi.Error, match=r"^P must have shape \(p, 3\), got \(30, 2\)$"):
        mbi.Deformer(U, T, P[:, :2])
    with pytest.raises(mbi.Error, match=r"^T must have shape \(m, 4\), got \(18, 3\)$"):
        mbi.Deformer(U, T[:, :3], P)
    with pytest.raises(mbi.Error, match=r"^U must be a 2D array \(n, d\), got shape \(48,\)$"):
        mbi.Deformer(U.ravel(), T, P)
    with pytest.raises(mbi.Error, match=r"^F must have shape \(t, 3\), got \(1, 4\)$"):
        mbi.Surface(U, [[0, 1, 2, 3]])
    with pytest.raises(mbi.Error, match=r"^rest_normals must have shape \(30, 3\), got \(2, 3\)$"):
        mbi.Deformer(U, T, P, rest_normals=np.ones((2, 3)))
    with pytest.raises(mbi.Error, match=r"^material: youngs_modulus must be finite and > 0 Pa, got -1"):
        mbi.Simulator(U, T, youngs_modulus=-1)
    with pytest.raises(mbi.Error, match=r"^material: poisson_ratio must lie in \(-1, 0.5\), got 0.6"):
        mbi.Simulator(U, T, poisson_ratio=0.6)
    with pytest.raises(mbi.Error, match=r"^stop \(1.0+ s\) is before start \(2.0+ s\)$"):
        mbi.Simulator(U, T).add_kinematic([0], start=2, stop=1)
    with pytest.raises(mbi.Error, match=r"^parameter dt must be finite and > 0 s$"):
        mbi.Simulator(U, T, dt=-1)


@pytest.mark.parametrize("call, message", [
    (lambda U, T, P: mbi.Deformer(U, T, P, "bi"),
     "Deformer() takes 3 positional arguments (U, T, P) but 4 were given; name the others: method=, alpha=, beta=, "
     "pin_boundary=, rest_normals=, threads=, max_outside=, max_memory="),
    (lambda U, T, P: mbi.Deformer(U, T, P, methd="bi"),
     "Deformer() got an unexpected keyword argument 'methd' (it takes U, T, P, method, alpha, beta, pin_boundary, "
     "rest_normals, threads, max_outside, max_memory)"),
    (lambda U, T, P: mbi.Deformer(U, T, P, alpha="big"), "Deformer(): alpha must be a number or None, got str"),
    (lambda U, T, P: mbi.Deformer(U, T), "Deformer() is missing the argument P"),
    (lambda U, T, P: mbi.Deformer(U, T, P).deform(U, np.empty((30, 3))),
     "Deformer.deform() takes 1 positional argument (X) but 2 were given; name the others: out=, normals=, "
     "normals_out=, dtype="),
    (lambda U, T, P: mbi.cage(U, None, 30), "cage() takes 2 positional arguments (V, F) but 3 were given; name the "
     "others: vertices=, mesher=, force_3d="),
    (lambda U, T, P: mbi.Simulator(U, T).step(1), "Simulator.step() takes 0 positional arguments () but 1 was given"),
    (lambda U, T, P: mbi.FastEvaluator.supported(2), "FastEvaluator.supported(): simd must be a string, got int"),
    (lambda U, T, P: mbi.write_surface("x.obj", U, T, N=None, encoding=1),
     "write_surface(): encoding must be a string, got int"),
])
def test_a_call_matching_no_signature_gets_one_short_line(bar, call, message):
    with pytest.raises(TypeError) as e:
        call(*bar)
    assert str(e.value) == message
    assert "Invoked with" not in str(e.value) and "\n" not in str(e.value)


def test_a_tensor_that_requires_grad_is_refused_in_one_line(bar):
    torch = pytest.importorskip("torch")
    U, T, P = bar
    X = torch.tensor(U, requires_grad=True)
    with pytest.raises(mbi.Error) as e:
        mbi.Deformer(U, T, P).deform(X)
    assert str(e.value) == ("X is a tensor that requires grad: numpy cannot read it; use mbi.torch "
                            "(mbi.torch.deform(deformer, X)) for gradients, or pass X.detach()")
    with pytest.raises(mbi.Error, match=r"^U is not an array: ") as e:
        mbi.embed(object.__new__(type("Odd", (), {"__array__": lambda self: 1 / 0})), T, P)
    assert "At:" not in str(e.value) and "\n" not in str(e.value)


def test_torch_functions_take_numpy_arrays(bar):
    torch = pytest.importorskip("torch")
    import mbi.torch
    U, T, P = bar
    deformer = mbi.Deformer(U, T, P)
    expect = deformer.deform(U + 0.1)
    for X in (U + 0.1, (U + 0.1).tolist(), torch.tensor(U + 0.1)):
        got = mbi.torch.deform(deformer, X)
        assert isinstance(got, torch.Tensor) and np.array_equal(got.numpy(), expect)
    assert np.array_equal(mbi.torch.Deform(deformer)(U + 0.1).numpy(), expect)
    assert np.array_equal(mbi.torch.deform(deformer, np.rint(U).astype(int)).numpy(), deformer.deform(np.rint(U)))
