"""The GIL is released while mbi works: calls from two Python threads on two objects run at the
same time and give the same results as one after the other; one object shared by two threads
stays consistent (its calls take turns)."""
import os
import threading
import time

import numpy as np
import pytest

import mbi
import meshes

SMALL = os.environ.get("MBI_SANITIZED") == "1"  # ASan is far slower: fewer points there


def run_threads(work, count=2):
    results, errors = [None] * count, []

    def body(k):
        try:
            results[k] = work(k)
        except Exception as e:  # reported by the main thread
            errors.append(e)

    threads = [threading.Thread(target=body, args=(k,)) for k in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    return results


def test_two_threads_run_at_once_and_agree():
    U, T = meshes.box(4, 3, 3)
    P = meshes.points(U, 30_000 if SMALL else 300_000)
    poses = [meshes.pose(U, seed=s) for s in range(6)]
    deformers = [mbi.Deformer(U, T, P, threads=1) for _ in range(2)]
    expect = [deformers[0].deform(X) for X in poses]
    intervals = [[], []]

    def work(k):
        out = []
        for X in poses:
            t0 = time.perf_counter()
            out.append(deformers[k].deform(X))
            intervals[k].append((t0, time.perf_counter()))
        return out

    results = run_threads(work)
    for k in range(2):
        for got, want in zip(results[k], expect):
            assert np.array_equal(got, want)
    # With the GIL held through a call, no call of one thread could start or end while a call
    # of the other is running: the intervals would be disjoint. Released, they overlap.
    overlap = sum(max(0.0, min(a1, b1) - max(a0, b0)) for a0, a1 in intervals[0] for b0, b1 in intervals[1])
    busy = sum(b - a for a, b in intervals[0])
    assert overlap > 0.2 * busy, (overlap, busy)


def test_one_object_shared_by_threads():
    U, T = meshes.jittered(3)
    n = 2_000 if SMALL else 20_000
    P = meshes.points(U, n)
    deformer = mbi.Deformer(U, T, P, rest_normals=np.tile([0.0, 0.0, 1.0], (n, 1)))
    solver = mbi.ModifiedBI(U, T)
    fast = mbi.FastEvaluator(deformer.embedding)
    poses = [meshes.pose(U, seed=s) for s in range(5)]
    expect = [(deformer.deform(X), deformer.deform(X, dtype=np.float32), solver.solve(X)) for X in poses]
    B = [deformer.bezier(X) for X in poses]

    def work(k):
        for _ in range(3):
            for X, b, (pos, pos32, M) in zip(poses, B, expect):
                assert np.array_equal(deformer.deform(X), pos)
                assert np.array_equal(deformer.deform(X, dtype=np.float32), pos32)
                assert np.array_equal(solver.solve(X), M)
                assert np.array_equal(fast.evaluate(b), pos32)
        return True

    assert all(run_threads(work, 3))


def test_set_threads_changes_the_count_not_the_results():
    U, T = meshes.box(3, 3, 3)
    P = meshes.points(U, 10_000 if SMALL else 100_000)
    X = meshes.pose(U)
    before = mbi.threads()
    try:
        mbi.set_threads(1)
        assert mbi.threads() == 1
        serial = mbi.Deformer(U, T, P).deform(X)
        mbi.set_threads(2)
        assert mbi.threads() == (2 if mbi.threads_available() else 1)  # a serial build runs on 1
        assert np.array_equal(mbi.Deformer(U, T, P).deform(X), serial)
        with pytest.raises(mbi.Error, match="threads"):
            mbi.set_threads(-1)
    finally:
        mbi.set_threads(0)
    assert mbi.threads() == before
