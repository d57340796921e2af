"""The array intake, case by case: zero strides (broadcast views) read in full, never past the
buffer; out= arrays that cannot be written (a zero stride, rows that overlap, memory shared with
an input, read-only, wrong dtype or shape) refused before anything is written; out= layouts
that cannot be mapped written through a copy; empty batches in both precisions.
test_arrays_hypothesis.py draws these layouts at random for every entry point."""
import numpy as np
import pytest
from numpy.lib.stride_tricks import as_strided

import mbi
import meshes


@pytest.fixture(scope="module")
def setup():
    U, T = meshes.jittered(3)
    P = meshes.points(U, 50)
    N = np.tile([0.0, 0.0, 1.0], (50, 1))
    return U, T, P, mbi.Deformer(U, T, P, rest_normals=N)


def unchanged(buffer, before):
    return np.array_equal(buffer, before, equal_nan=True)


def test_broadcast_inputs_are_read_in_full(setup):
    U, T, P, deformer = setup
    row = np.array([0.3, -0.2, 0.5])
    X = np.broadcast_to(row, U.shape)  # strides (0, 8): one row of memory
    assert X.strides[0] == 0
    expect = deformer.deform(np.tile(row, (len(U), 1)))
    assert np.allclose(deformer.deform(X), expect, rtol=0, atol=1e-12)
    assert np.allclose(deformer.deform(X, dtype=np.float32), expect, atol=1e-5)
    solver = mbi.ModifiedBI(U, T)
    assert np.allclose(solver.solve(X), solver.solve(np.tile(row, (len(U), 1))), atol=1e-12)
    G = np.broadcast_to(1.0, (50, 3))  # strides (0, 0): the gradient of positions.sum()
    assert np.allclose(deformer.vjp(G), deformer.vjp(np.ones((50, 3))), atol=1e-12)
    batch = np.broadcast_to(U, (4,) + U.shape)  # frames with a zero stride
    assert np.allclose(deformer.deform(batch), np.stack([deformer.deform(U)] * 4), atol=1e-12)


def test_zero_stride_out_is_refused(setup):
    U, T, P, deformer = setup
    memory = np.zeros(3)
    out = as_strided(memory, (50, 3), (0, 8))  # writable, every row the same three doubles
    with pytest.raises(mbi.Error, match=r"out overlaps itself"):
        deformer.deform(U, out=out)
    with pytest.raises(mbi.Error, match=r"out overlaps itself"):
        mbi.evaluate(deformer.bezier(U), deformer.embedding, out=out)
    memory32 = np.zeros(3, np.float32)
    with pytest.raises(mbi.Error, match=r"out overlaps itself"):
        deformer.deform(U, out=as_strided(memory32, (50, 3), (0, 4)))
    with pytest.raises(mbi.Error, match=r"out overlaps itself"):
        deformer.vjp(np.ones((50, 3)), out=as_strided(memory, (45, 3), (0, 8)))
    assert not memory.any() and not memory32.any()


def test_out_overlapping_itself_or_an_input_is_refused(setup):
    U, T, P, deformer = setup
    memory = np.full(200, np.nan)
    rows = as_strided(memory, (50, 3), (8, 8))  # row i starts one double after row i - 1
    with pytest.raises(mbi.Error, match=r"out overlaps itself"):
        deformer.deform(U, out=rows)
    assert unchanged(memory, np.full(200, np.nan))
    # out sharing memory with X: X is the first rows of out's buffer
    buffer = np.zeros((60, 3))
    buffer[:45] = U
    before = buffer.copy()
    with pytest.raises(mbi.Error, match=r"out shares memory with X"):
        deformer.deform(buffer[:45], out=buffer[10:])
    with pytest.raises(mbi.Error, match=r"out shares memory with G"):
        deformer.vjp(buffer[:50], out=buffer[5:50])
    flat = np.zeros(600)
    flat[:135] = U.ravel()
    with pytest.raises(mbi.Error, match=r"out shares memory with X"):
        mbi.ModifiedBI(U, T).solve(flat[:135].reshape(45, 3), out=flat[130:535].reshape(135, 3))
    assert np.array_equal(flat[:135], U.ravel()) and not flat[135:].any()
    with pytest.raises(mbi.Error, match=r"out shares memory with normals_out"):
        deformer.deform(U, out=buffer[:50], normals_out=buffer[10:])
    assert np.array_equal(buffer, before)
    # a float32 out viewing X's memory
    X32 = np.zeros((45 * 3 * 2,))
    X32[: 45 * 3] = U.ravel()
    with pytest.raises(mbi.Error, match=r"out shares memory with X"):
        deformer.deform(X32[: 45 * 3].reshape(45, 3), out=X32.view(np.float32)[: 150].reshape(50, 3))


def test_interleaved_outputs_are_accepted(setup):
    U, T, P, deformer = setup
    vertices = np.zeros((50, 6))  # positions and normals interleaved, as a vertex buffer
    positions, normals = deformer.deform(U, out=vertices[:, :3], normals_out=vertices[:, 3:])
    assert positions.base is vertices and normals.base is vertices
    expect_p, expect_n = deformer.deform(U, normals=True)
    assert np.allclose(vertices[:, :3], expect_p, atol=1e-12) and np.allclose(vertices[:, 3:], expect_n, atol=1e-12)


def test_read_only_wrong_dtype_and_shape_are_refused_before_writing(setup):
    U, T, P, deformer = setup
    out = np.full((50, 3), np.nan)
    out.flags.writeable = False
    with pytest.raises(mbi.Error, match=r"out is read-only"):
        deformer.deform(U, out=out)
    with pytest.raises(mbi.Error, match=r"out is read-only"):
        deformer.deform(U, out=np.broadcast_to(np.zeros(3), (50, 3)))
    for dtype in (np.int64, np.float16, np.complex128):
        bad = np.zeros((50, 3), dtype)
        with pytest.raises(mbi.Error, match=r"out must be a float64 array"):
            mbi.evaluate(deformer.bezier(U), deformer.embedding, out=bad)
        assert not bad.any()
    bad = np.zeros((50, 3), np.float32)
    with pytest.raises(mbi.Error, match=r"out must be a float64 array"):
        deformer.vjp(np.ones((50, 3)), out=bad[:45])
    with pytest.raises(mbi.Error, match=r"out must have shape \(2, 50, 3\), got \(100, 3\)"):
        deformer.deform(np.stack([U, U]), out=np.zeros((100, 3)))


@pytest.mark.parametrize("layout", ["reversed", "frames apart", "unaligned", "byte-swapped", "F"])
def test_out_layouts_that_cannot_be_mapped_are_written(setup, layout):
    U, T, P, deformer = setup
    poses = np.stack([meshes.pose(U, seed=s) for s in range(3)])
    for dtype in (np.float64, np.float32):
        expect = deformer.deform(poses, dtype=dtype)
        if layout == "reversed":
            out = np.zeros((3, 50, 3), dtype)[:, ::-1, ::-1]
        elif layout == "frames apart":
            out = np.zeros((6, 50, 3), dtype)[::2]
        elif layout == "unaligned":
            out = np.frombuffer(bytearray(expect.nbytes + 1), dtype, expect.size, 1).reshape(expect.shape)
        elif layout == "byte-swapped":
            out = np.zeros((3, 50, 3), np.dtype(dtype).newbyteorder())
        else:
            out = np.zeros((3, 50, 3), dtype, order="F")
        assert deformer.deform(poses, out=out) is out
        assert np.array_equal(out, expect)


def test_empty_batches(setup):
    U, T, P, deformer = setup
    empty = np.zeros((0, 45, 3))
    assert deformer.deform(empty).shape == (0, 50, 3)
    for X in (empty, empty.astype(np.float32), np.zeros((4, 45, 3))[:0]):
        positions = deformer.deform(X, dtype=np.float32)
        assert positions.shape == (0, 50, 3) and positions.dtype == np.float32
    out = np.zeros((0, 50, 3), np.float32)
    assert deformer.deform(empty, out=out) is out
    positions, normals = deformer.deform(empty, normals=True, dtype=np.float32)
    assert positions.shape == normals.shape == (0, 50, 3)
    assert deformer.vjp(np.zeros((0, 50, 3))).shape == (0, 45, 3)
    with pytest.raises(mbi.Error, match=r"X must have shape \(frames, 45, 3\)"):
        deformer.deform(np.zeros((0, 44, 3)), dtype=np.float32)


def test_unaligned_and_byte_swapped_inputs(setup):
    U, T, P, deformer = setup
    X = meshes.pose(U)
    raw = np.frombuffer(bytearray(X.nbytes + 1), np.float64, X.size, 1).reshape(X.shape)
    raw[...] = X
    assert not raw.flags.aligned
    assert np.array_equal(deformer.deform(raw), deformer.deform(X))
    assert np.array_equal(deformer.deform(X.astype(">f8")), deformer.deform(X))
    Tb = T.astype(">i4")
    assert np.array_equal(mbi.embed(U, Tb, P).bary, mbi.embed(U, T, P).bary)
