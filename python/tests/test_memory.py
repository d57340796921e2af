"""A modified-BI run's memory from Python: the estimate against the factor ModifiedBI builds, the
limit a run may take, and max_memory sending the automatic path to PCG; bad sizes name the
argument."""
import numpy as np
import pytest

import mbi

GIB = 1024.0 ** 3


def test_estimate_bounds_the_factor_that_modified_bi_builds():
    U, T = mbi.box_mesh(9, 8, 7)
    solver = mbi.ModifiedBI(U, T, solve_path="sparse")
    e = mbi.estimate_memory(U, T, 10_000, solve_path="sparse")
    assert e.unknowns == 3 * len(U)
    # an upper bound of the values the factor stores, within 2x (tests/interp/test_memory.cpp in C++)
    assert solver.factor_nonzeros <= e.factor_nonzeros <= 2 * solver.factor_nonzeros
    # the factor as stored: at least its nonzeros, an index a row at least
    assert solver.factor_stored_values >= solver.factor_nonzeros
    assert solver.factor_index_bytes >= 4 * e.unknowns
    assert e.ordering in ("AMD", "METIS", "AMD (Eigen)")
    parts = e.process_bytes + e.model_bytes + e.factor_bytes + e.assembly_bytes + e.dense_operator_bytes
    assert e.peak_bytes == pytest.approx(parts, rel=1e-12)
    assert e.factor_bytes >= 8 * e.factor_nonzeros
    # the dense points count: more points, more model bytes, the same factor
    more = mbi.estimate_memory(U, T, 1_000_000, solve_path="sparse")
    assert more.model_bytes > e.model_bytes and more.factor_nonzeros == e.factor_nonzeros
    assert "MemoryEstimate(peak=" in repr(e)


def test_memory_limit_takes_the_callers_size_else_what_the_machine_has():
    assert mbi.memory_limit(5e9) == (5e9, "--max-memory")
    assert mbi.memory_limit("8G") == (8 * GIB, "--max-memory")
    assert mbi.memory_limit(np.int64(2 ** 30)) == (GIB, "--max-memory")
    have, name = mbi.memory_limit()
    assert have > 0 and name != "--max-memory"


def test_max_memory_below_the_factor_takes_the_iterative_path():
    U, T = mbi.box_mesh(11, 11, 11)  # 1,728 vertices: above the dense operator's size
    rng = np.random.default_rng(3)
    X = U + 0.05 * np.sin(3 * U) + 0.01 * rng.standard_normal(U.shape)
    direct = mbi.ModifiedBI(U, T)
    assert not direct.factorization.startswith("none")
    pcg = mbi.ModifiedBI(U, T, max_memory="1M")
    assert pcg.factorization.startswith("none: PCG")
    # the same deformation: positions within 1e-6 of the model size (method.md fact 19), here
    # through the Bezier points that bound them
    B_direct = direct.bezier(X, direct.solve(X))
    B_pcg = pcg.bezier(X, pcg.solve(X))
    assert np.abs(B_pcg - B_direct).max() <= 1e-6 * np.sqrt(3)
    P = U[::7] * 0.9 + 0.05
    deformer = mbi.Deformer(U, T, P, max_memory=2 ** 20)
    assert np.abs(deformer.deform(X) - mbi.Deformer(U, T, P).deform(X)).max() <= 1e-6 * np.sqrt(3)


@pytest.mark.parametrize("bad", [-1, 0, float("nan"), float("inf"), "lots", "-2G", True, np.ones(1), [1]])
def test_bad_max_memory_names_the_argument(bad):
    U, T = mbi.box_mesh(2, 2, 2)
    with pytest.raises(mbi.Error, match="max_memory"):
        mbi.ModifiedBI(U, T, max_memory=bad)
    with pytest.raises(mbi.Error, match="max_memory"):
        mbi.memory_limit(bad)


def test_estimate_refuses_bad_input_by_name():
    U, T = mbi.box_mesh(2, 2, 2)
    with pytest.raises(mbi.Error, match="dense_points"):
        mbi.estimate_memory(U, T, -1)
    bad = T.copy()
    bad[0, 0] = len(U)
    with pytest.raises(mbi.Error):
        mbi.estimate_memory(U, bad)
    with pytest.raises(mbi.Error, match="solve_path"):
        mbi.estimate_memory(U, T, solve_path="fast")
