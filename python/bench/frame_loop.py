"""A frame loop from Python with out=: per call against the same C++ call, what 100 calls
allocate and fault, and a first 600 MB batch against the same frames looped.

    cmake --preset release -DMBI_PYTHON_TIMING=ON && cmake --build --preset release --target mbi_python
    PYTHONPATH=build/release/python python3 python/bench/frame_loop.py [--calls N] [--threads T]
        [--batch-mb MB] [--batch-runs R] [--skip-batch] [--quick]

The C++ columns need the benchmark's clocks (CMake MBI_PYTHON_TIMING=ON); with the shipped module
(no clocks) the Python columns, the allocations and the batch are measured alone. --quick (CI,
scripts/bench.sh --quick): a few seconds, small counts, a 24 MB batch, no idle wait.
Sizes as in python/tests/faults.py: 1,000 random points in a 7 x 7 x 6-cell box (1,764 tetrahedra).

1. Deformer.deform(X, out=) and Deformer.vjp(G, out=) for BI, Phong and modified-BI, in pairs
   of one Python call and the same C++ call timed in C++ (mbi._mbi._timing), adjacent in time,
   every other pair the C++ call first: medians of the Python calls, of the C++ calls, of the
   difference within each pair, and of each Python call less its own C++ section (the bindings
   clock the part they run without the GIL: "outside C++" is what the binding adds to that very
   call); "fresh" is a new process's first 200 pairs after construction and one call, "warm" N
   pairs (default 10,000) after 2,000.
2. 100 calls with out= (and mbi.evaluate of the method's Bezier points): the peak of the memory
   tracemalloc traces (numpy's arrays and Python's objects) and minor page faults per call.
3. deform of a batch of frames into a new array (mbi allocates it) of about 600 MB, in a new
   process, per frame, against the same frames one at a time into one out= array; R processes
   (default 4) one after the other. Beside it, the machine's own cost of a first touch: a new
   process filling a new numpy array of the same size, once after --idle seconds without work
   (a virtual machine's host may have taken back the memory freed before) and once right after.
"""
import argparse
import json
import resource
import subprocess
import sys
import time
import tracemalloc

import numpy as np

import mbi
from mbi import _mbi

METHODS = ("bi", "phong", "modified-bi")


def setup(method, threads, points=1000):
    U, T = mbi.box_mesh(7, 7, 6)
    rng = np.random.default_rng(0)
    P = rng.uniform(0.05, 0.95, (points, 3))
    deformer = mbi.Deformer(U, T, P, method=method, threads=threads)
    X = U + 0.02 * rng.standard_normal(U.shape)
    return deformer, X, rng.standard_normal((points, 3)), np.empty((points, 3)), np.empty_like(U)


def calls(deformer, X, G, out, dX):
    """(name, Python call, one C++ call timed in C++ (seconds)) for deform and vjp."""
    return [("deform", lambda: deformer.deform(X, out=out), lambda: _mbi._timing.deform(deformer, X, out, 1)[0]),
            ("vjp", lambda: deformer.vjp(G, out=dX), lambda: _mbi._timing.vjp(deformer, G, dX, 1)[0])]


def timing():
    """The C++ loops and the section clock, or None in a module built without them."""
    return getattr(_mbi, "_timing", None)


def paired(py_call, cpp_call, n):
    """Medians (us) over n pairs of one Python call and the same C++ call, adjacent in time (which
    goes first alternates), so that a slow spell of the machine falls on both: the Python call,
    the C++ call, the difference within each pair, and each Python call less its own C++ section
    (NaN without clocks)."""
    py, cpp, section = np.empty(n), np.full(n, np.nan), np.full(n, np.nan)
    clock, clocks = time.perf_counter_ns, timing()
    for k in range(n):
        if clocks and k % 2:
            cpp[k] = cpp_call()
        t0 = clock()
        py_call()
        py[k] = (clock() - t0) * 1e-9
        if clocks:
            section[k] = clocks.last_call()
            if not k % 2:
                cpp[k] = cpp_call()
    med = lambda v: float(np.median(v)) * 1e6
    return med(py), med(cpp), med(py - cpp), med(py - section)


def per_call(method, threads, n, fresh):
    """fresh: the first 200 pairs after construction and one call; else n pairs after 2,000."""
    deformer, X, G, out, dX = setup(method, threads)
    result = {}
    for name, py_call, cpp_call in calls(deformer, X, G, out, dX):
        py_call()
        if fresh:
            result[name] = paired(py_call, cpp_call, 200)
        else:
            paired(py_call, cpp_call, min(2000, n))  # warm-up
            result[name] = paired(py_call, cpp_call, n)
    return result


def loop_costs(method, threads):
    """numpy bytes at the peak of 100 calls, and minor faults a call, after one call."""
    deformer, X, G, out, dX = setup(method, threads)
    B = deformer.bezier(X)
    result = {}
    runs = [(name, py_call) for name, py_call, _ in calls(deformer, X, G, out, dX)]
    for name, py_call in runs + [("evaluate", lambda: mbi.evaluate(B, deformer.embedding, out=out))]:
        py_call()
        tracemalloc.start()
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        for _ in range(100):
            py_call()
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        result[name] = (peak, faults / 100)
    return result


def batch(megabytes, points=100_000):
    """ms a frame: a first batch into a new array, and the same frames looped into one out=."""
    U, T = mbi.box_mesh(7, 7, 6)
    rng = np.random.default_rng(0)
    deformer = mbi.Deformer(U, T, rng.uniform(0.05, 0.95, (points, 3)))
    frames = max(1, int(megabytes * 1e6 / (points * 3 * 8)))
    X = U + 0.01 * rng.standard_normal((frames,) + U.shape)
    t0 = time.perf_counter()
    first = deformer.deform(X)
    first_ms = (time.perf_counter() - t0) / frames * 1e3
    one = np.empty((points, 3))
    deformer.deform(X[0], out=one)
    t0 = time.perf_counter()
    for k in range(frames):
        deformer.deform(X[k], out=one)
    looped_ms = (time.perf_counter() - t0) / frames * 1e3
    assert np.array_equal(one, first[-1])
    return {"frames": frames, "megabytes": first.nbytes / 1e6, "first": first_ms, "looped": looped_ms}


def first_fill(megabytes):
    """Seconds of the first and of a second fill of a new array of that size."""
    a = np.empty(int(megabytes * 1e6 / 8))
    t0 = time.perf_counter()
    a.fill(0)
    t1 = time.perf_counter()
    a.fill(1)
    return {"first": t1 - t0, "again": time.perf_counter() - t1}


def child(args):
    """Runs one measurement in this (new) process and prints it as JSON."""
    kind = args.child
    if kind == "fresh":
        print(json.dumps(per_call(args.method, args.threads, 0, True)))
    elif kind == "loop":
        print(json.dumps(loop_costs(args.method, args.threads)))
    elif kind == "fill":
        print(json.dumps(first_fill(args.batch_mb)))
    else:
        print(json.dumps(batch(args.batch_mb)))


def in_new_process(*argv):
    result = subprocess.run([sys.executable, __file__, *argv], capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def print_per_call(args):
    print(f"1,000 points, 1,764 tetrahedra; Deformer threads={args.threads} ({mbi.threads()} cores); "
          f"C++ loops: {'yes' if timing() else 'none in this module (MBI_PYTHON_TIMING=OFF)'}")
    print()
    print("| method | call | process | from Python (us) | C++ alone (us) | paired difference (us) | outside C++ (us) |")
    print("|---|---|---|---|---|---|---|")
    for method in METHODS:
        fresh = in_new_process("--child", "fresh", "--method", method, "--threads", str(args.threads))
        warm = per_call(method, args.threads, args.calls, False)
        for name in ("deform", "vjp"):
            for process, (py, cpp, difference, outside) in (("fresh", fresh[name]), ("warm", warm[name])):
                columns = [f"{py:.2f}"] + ["-" if np.isnan(v) else f"{v:{f}}" for v, f in
                                           ((cpp, ".2f"), (difference, "+.2f"), (outside, "+.2f"))]
                print(f"| {method} | {name}(out=) | {process} | " + " | ".join(columns) + " |")
    print()


def print_loop_costs(args):
    print("| method | call | numpy bytes at the peak of 100 calls | minor page faults a call |")
    print("|---|---|---|---|")
    for method in METHODS:
        loop = in_new_process("--child", "loop", "--method", method, "--threads", str(args.threads))
        for name in ("deform", "vjp", "evaluate"):
            peak, faults = loop[name]
            call = "mbi.evaluate(B, embedding, out=)" if name == "evaluate" else f"Deformer.{name}(out=)"
            print(f"| {method} | {call} | {peak} | {faults:.2f} |")
    print()


def print_batches(args):
    print("| first batch deform, new process | ms a frame | looped into one out=, ms a frame | ratio |")
    print("|---|---|---|---|")
    for run in range(args.batch_runs):
        b = in_new_process("--child", "batch", "--batch-mb", str(args.batch_mb))
        print(f"| run {run + 1}: modified-bi, 100,000 points, {b['frames']} frames, {b['megabytes']:.0f} MB | "
              f"{b['first']:.2f} | {b['looped']:.2f} | {b['first'] / b['looped']:.2f}x |")
    print()
    time.sleep(args.idle)
    cold = in_new_process("--child", "fill", "--batch-mb", str(args.batch_mb))
    warm = in_new_process("--child", "fill", "--batch-mb", str(args.batch_mb))
    print(f"numpy fill of a new {args.batch_mb:.0f} MB array in a new process: after {args.idle:.0f} s idle "
          f"{cold['first']:.3f} s, right after {warm['first']:.3f} s; a second fill {warm['again']:.3f} s")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=10_000)
    parser.add_argument("--batch-mb", type=float, default=600)
    parser.add_argument("--batch-runs", type=int, default=4)
    parser.add_argument("--threads", type=int, default=0, help="the Deformer's threads (0: all cores)")
    parser.add_argument("--skip-batch", action="store_true")
    parser.add_argument("--idle", type=float, default=20)
    parser.add_argument("--quick", action="store_true", help="a few seconds (CI): small counts, a 24 MB batch")
    parser.add_argument("--child", choices=("fresh", "loop", "batch", "fill"), help=argparse.SUPPRESS)
    parser.add_argument("--method", default="modified-bi", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child(args)
    if args.quick:
        args.calls, args.batch_mb, args.batch_runs, args.idle = 200, 24, 1, 0
    print_per_call(args)
    print_loop_costs(args)
    if not args.skip_batch:
        print_batches(args)


if __name__ == "__main__":
    main()
