"""What the Python layer costs: the same C++ calls timed from Python and from C++, and the
vector-Jacobian product against the forward map.

    cmake --preset release -DMBI_PYTHON_TIMING=ON && cmake --build --preset release --target mbi_python
    PYTHONPATH=build/release/python python3 python/bench/overhead.py [--calls N] [--points P]

The module needs the benchmark's clocks (CMake MBI_PYTHON_TIMING=ON; the shipped one has none).

1. Per-call overhead (medians over N calls, default 10,000, each timed alone): ModifiedBI.solve
   at 448 control vertices (a 7 x 7 x 6-cell box) and FastEvaluator.evaluate of P points (default
   1,000,000) into an out= array. From Python, and the same C++ call in a C++ loop
   (mbi._mbi._timing), in alternating blocks of 100 calls: "difference" is the difference of the
   two medians. "Added within the call" is the median of each Python call's time less the time
   it spent in C++ itself (the bindings clock their section without the GIL): what Python adds to
   that very call, free of the noise of a shared machine between two calls.
2. Dense arrays allocated per call with out=: numpy's allocations as tracemalloc counts them.
3. Deformer.vjp against Deformer.deform (float64, modified-BI, same sizes): median of 30 calls.
"""
import argparse
import time
import tracemalloc

import numpy as np

import mbi
from mbi import _mbi


def python_times(call, calls):
    """Seconds of each of `calls` calls from Python, and of the C++ part of each (the section the
    bindings run without the GIL, mbi._mbi._timing.last_call)."""
    total, section = np.empty(calls), np.empty(calls)
    clock, last_call = time.perf_counter_ns, _mbi._timing.last_call
    for k in range(calls):
        t0 = clock()
        call()
        t1 = clock()
        section[k] = last_call()
        total[k] = (t1 - t0) * 1e-9
    return total, section


def compare(py_call, cpp_times, calls, block=100):
    """`calls` calls from Python and `calls` in a C++ loop, in alternating blocks (a slow spell of
    a shared machine falls on both alike). Returns the medians (s) of the Python times, of the
    C++ times, and of each Python call's time less its own C++ part."""
    py, cpp, own = [], [], []
    for _ in range(max(1, calls // block)):
        total, section = python_times(py_call, block)
        py.append(total)
        own.append(total - section)
        cpp.append(cpp_times(block))
    return tuple(float(np.median(np.concatenate(v))) for v in (py, cpp, own))


def allocated_per_call(call, calls=100):
    call()
    tracemalloc.start()
    for _ in range(calls):
        call()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=10_000)
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--vjp-calls", type=int, default=30)
    args = parser.parse_args()
    if getattr(_mbi, "_timing", None) is None:
        parser.exit(2, "overhead.py: this module has no clocks: build it with "
                       "cmake --preset release -DMBI_PYTHON_TIMING=ON\n")

    U, T = mbi.box_mesh(7, 7, 6)
    rng = np.random.default_rng(0)
    X = U + 0.02 * rng.standard_normal(U.shape)
    X[:, 1] += 0.3 * U[:, 0] ** 2
    solver = mbi.ModifiedBI(U, T)
    M = solver.solve(X)
    P = rng.uniform(0, 1, size=(args.points, 3))
    emb = mbi.embed(U, T, P)
    fast = mbi.FastEvaluator(emb)
    B = solver.bezier(X, M)
    out32 = np.empty((args.points, 3), np.float32)
    small, out_small = mbi.FastEvaluator(mbi.embed(U, T, P[:1000])), np.empty((1000, 3), np.float32)
    print(f"control mesh {len(U)} vertices, {len(T)} tetrahedra; {args.points} points; "
          f"solve path {'dense operator' if solver.dense_operator else 'sparse'}; kernel {fast.simd}, "
          f"{fast.threads} threads; medians over {args.calls} calls")
    print()
    print("| call | from Python (us) | C++ alone (us) | difference (us) | added within the call (us) |")
    print("|---|---|---|---|---|")
    rows = [
        ("ModifiedBI.solve(X, out=M)", lambda: solver.solve(X, out=M),
         lambda n: _mbi._timing.solve(solver, X, n)),
        ("ModifiedBI.solve(X)", lambda: solver.solve(X), lambda n: _mbi._timing.solve(solver, X, n)),
        (f"FastEvaluator.evaluate(B, out=...) ({args.points} points)", lambda: fast.evaluate(B, out=out32),
         lambda n: _mbi._timing.fast_evaluate(fast, B, out32, n)),
        ("FastEvaluator.evaluate(B, out=...) (1000 points: the fixed cost shows)", lambda: small.evaluate(B, out=out_small),
         lambda n: _mbi._timing.fast_evaluate(small, B, out_small, n)),
    ]
    for name, py_call, cpp_times in rows:
        py, cpp, own = compare(py_call, cpp_times, args.calls)
        print(f"| {name} | {py * 1e6:.2f} | {cpp * 1e6:.2f} | {(py - cpp) * 1e6:+.2f} | {own * 1e6:+.2f} |")
    print()
    M_out = np.empty_like(M)
    print("numpy bytes allocated at the peak of 100 calls (tracemalloc): "
          f"solve(X, out=M) {allocated_per_call(lambda: solver.solve(X, out=M_out))}, "
          f"evaluate(B, out=...) {allocated_per_call(lambda: fast.evaluate(B, out=out32))}, "
          f"evaluate(B) without out= {allocated_per_call(lambda: fast.evaluate(B))} "
          f"(one result: {out32.nbytes})")
    print()

    deformer = mbi.Deformer(U, T, P)
    pos, G = np.empty((args.points, 3)), rng.standard_normal((args.points, 3))
    dX = np.empty_like(U)
    forward = np.median(python_times(lambda: deformer.deform(X, out=pos), args.vjp_calls)[0])
    vjp = np.median(python_times(lambda: deformer.vjp(G, out=dX), args.vjp_calls)[0])
    print(f"Deformer (modified-bi, float64), medians of {args.vjp_calls} calls: deform {forward * 1e3:.2f} ms, "
          f"vjp {vjp * 1e3:.2f} ms: vjp / deform = {vjp / forward:.2f}")


if __name__ == "__main__":
    main()
