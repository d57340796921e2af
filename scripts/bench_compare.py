#!/usr/bin/env python3
"""Two builds of mbi-bench measured in the same run: old and new alternate, round after round.

    bench_compare.py --old OLD/mbi-bench --new build/release/mbi-bench [--filter REGEX]
                     [--rounds N] [--out FILE.json]

Each round runs the old binary, then the new one, on the benchmarks matching REGEX (default: the
isolated rows of the speed targets: evaluation, solve, precompute, embedding, simulator step);
a slow spell of a shared machine then falls on both. Prints, per benchmark, the median over the
rounds of each build and new / old; --out writes them as JSON (scripts/bench_report.py reads it
with --compare). Run nothing else meanwhile.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

DEFAULT_FILTER = ("BM_Eval/points:1000000/control:450/mbi:1/threads:(0|1)/double:0/normals:0"
                  "|BM_Eval/points:1000000/control:450/mbi:1/threads:0/double:1/normals:0"
                  "|BM_ScaleSolve/control:(450|1300|2000|10000)/"
                  "|BM_ScalePrecompute/control:(450|1300|2000|10000)/cholmod:1"
                  "|BM_Embed/points:1000000/tets:5000|BM_SimStep/mesh:(1|2)/solver:2/tol:8"
                  "|BM_SceneFrame/large")


def run(binary, flt):
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        path = f.name
    try:
        subprocess.run([binary, f"--benchmark_filter={flt}", f"--benchmark_out={path}",
                        "--benchmark_out_format=json"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(path) as f:
            data = json.load(f)
    finally:
        os.unlink(path)
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
    return {b["name"]: b["real_time"] * scale[b.get("time_unit", "ns")]
            for b in data["benchmarks"] if not b.get("error_occurred")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True)
    ap.add_argument("--new", required=True)
    ap.add_argument("--filter", default=DEFAULT_FILTER)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out")
    a = ap.parse_args()
    times = {"old": {}, "new": {}}
    for r in range(a.rounds):
        for which, binary in (("old", a.old), ("new", a.new)):
            for name, ms in run(binary, a.filter).items():
                times[which].setdefault(name, []).append(ms)
        print(f"bench_compare: round {r + 1} of {a.rounds} done", file=sys.stderr)
    rows = []
    for name in times["new"]:
        if name not in times["old"]:
            continue
        o, n = statistics.median(times["old"][name]), statistics.median(times["new"][name])
        rows.append({"name": name, "old_ms": o, "new_ms": n, "ratio": n / o,
                     "old_all": times["old"][name], "new_all": times["new"][name]})
    for row in rows:
        print(f"{row['name'][:70]:70s} old {row['old_ms']:10.4f} ms  new {row['new_ms']:10.4f} ms  "
              f"new/old {row['ratio']:.2f}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"old": a.old, "new": a.new, "filter": a.filter, "rounds": a.rounds,
                       "command": " ".join(sys.argv), "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
