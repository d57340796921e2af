"""Page faults of a per-frame loop with out=, in a fresh process (python/tests/faults.py): after
the first call, deform, vjp and mbi.evaluate should touch no new page (the glibc allocator maps
and unmaps the large blocks a call allocates, so every fresh temporary faults its pages in again).
At 1,000 points in 1,764 tetrahedra, as in the benchmarks, for the three methods."""
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))


def faults_per_call(method, call, env=None):
    result = subprocess.run([sys.executable, os.path.join(HERE, "faults.py"), method, call],
                            capture_output=True, text=True, timeout=300, env=dict(os.environ, **(env or {})))
    assert result.returncode == 0, result.stderr
    return float(result.stdout)


@pytest.mark.parametrize("method", ["bi", "phong", "modified-bi"])
@pytest.mark.parametrize("call", ["deform", "vjp", "evaluate"])
def test_a_loop_with_out_faults_no_page_after_the_first_call(method, call):
    assert faults_per_call(method, call) < 1


def test_the_count_sees_page_faults():
    # a fixed mmap threshold: each new 1.7 MB result is mapped afresh, 400 pages faulted in a call
    assert faults_per_call("modified-bi", "fresh", {"MALLOC_MMAP_THRESHOLD_": "131072"}) > 100


def test_calls_with_out_allocate_no_block_over_4_kb():
    # glibc maps every block over 4 KB on its own (the heap's top kept trimmed, so that none comes
    # from it) and unmaps it when freed: a temporary of M, B, a pose or the positions in a call
    # faults its pages in again every call, as a new M does (solve_new, 32 KB: 8 pages)
    calls = ["solve", "phong", "bezier", "deform", "vjp", "evaluate", "solve_new"]
    result = subprocess.run([sys.executable, os.path.join(HERE, "faults.py"), "modified-bi", *calls],
                            capture_output=True, text=True, timeout=300,
                            env=dict(os.environ, MALLOC_MMAP_THRESHOLD_="4096", MALLOC_TRIM_THRESHOLD_="0",
                                     MALLOC_TOP_PAD_="0"))
    assert result.returncode == 0, result.stderr
    faults = dict(zip(calls, map(float, result.stdout.split())))
    assert faults.pop("solve_new") >= 4, faults
    assert all(f < 1 for f in faults.values()), faults
