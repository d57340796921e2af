#!/usr/bin/env python3
"""The threads report: the application figures of one run, before and after, against their targets.

    bench_threads_report.py --harness DIR [--ref REV] [--jobs FILE.json] [--compare FILE.json]
                            [--title TEXT] > bench/results/DATE-vm-threads.md

Reads what scripts/bench_harness.sh (DIR/harness-new.json and, with --ref, DIR/harness-REV.json),
scripts/bench_jobs.sh and scripts/bench_compare.py wrote in the same session and prints one
Markdown page: each target with the measured figure, the old library's where there is one, and
whether it is met. Nothing is measured here.
"""
import argparse
import json
import os
import statistics
import sys


def load(path):
    with open(path) as f:
        return json.load(f)


def row(rows, scenario, name, load_="quiet", key="ms"):
    for r in rows:
        if r["scenario"] == scenario and r["name"] == name and r["load"] == load_:
            return r["mean_ms"] if key == "mean" and r["mean_ms"] else r["ms"]
    return None


def harness_ratios(rows):
    """(label, ratio, target) for every harness target; None where the harness has no row."""
    out = []

    def ratio(a, b):
        return a / b if a is not None and b else None

    out.append(("interleaved frame (solve + Bezier + fast evaluation, 448 / 1M) / its phases alone",
                ratio(row(rows, "frame", "interleaved frame"), row(rows, "frame", "sum of the phases alone")), 1.25))
    out.append(("first solve after a precompute at 1,331 / the solves after it",
                ratio(row(rows, "first_solve", "first solve after it"), row(rows, "first_solve", "solves after that")), 1.2))
    for name in ("precompute 448", "precompute 1331", "solve 448 (dense operator)", "solve 1331 (sparse sweeps)",
                 "evaluate 1M (fast, all threads)"):
        out.append((f"{name}, one core taken by a spinning thread of the process / quiet (means)",
                    ratio(row(rows, "loaded", name, "thread", "mean"), row(rows, "loaded", name, "quiet", "mean")), 2.2))
    out.append(("`interp::evaluate<float>` 1M, all threads / FastEvaluator",
                ratio(row(rows, "one_shot", "evaluate<float> (all threads)"),
                      row(rows, "one_shot", "FastEvaluator (all threads)")), 2.0))
    return out


def jobs_ratio(jobs, binary):
    alone = [r["alone_s"] for r in jobs["runs"] if r["binary"] == binary]
    slower = [max(r["together_s"]) for r in jobs["runs"] if r["binary"] == binary]
    if not alone:
        return None, None, None
    a, s = statistics.median(alone), statistics.median(slower)
    return a, s, s / a


def fmt(x, digits=2):
    return "-" if x is None else f"{x:.{digits}f}"


def harness_table(new, old, ref):
    print("| target | " + (f"before ({ref}) | " if old else "") + "after | bound | met? |")
    print("|---|" + ("---|" if old else "") + "---|---|---|")
    before = dict((l, r) for l, r, _ in harness_ratios(old["rows"])) if old else {}
    for label, r, bound in harness_ratios(new["rows"]):
        met = "-" if r is None else ("**yes**" if r <= bound else "**no**")
        print(f"| {label} | " + (f"{fmt(before.get(label))}x | " if old else "") + f"{fmt(r)}x | <= {bound} | {met} |")


def loads_table(new, old, ref):
    print("| stage | load | " + (f"before ({ref}), ms | " if old else "") + "after, ms |")
    print("|---|---|" + ("---|" if old else "") + "---|")
    for r in new["rows"]:
        if r["scenario"] != "loaded":
            continue
        b = row(old["rows"], "loaded", r["name"], r["load"], "mean") if old else None
        print(f"| {r['name']} | {r['load']} | " + (f"{fmt(b, 3)} | " if old else "") + f"{fmt(r['mean_ms'] or r['ms'], 3)} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--harness", required=True)
    ap.add_argument("--ref")
    ap.add_argument("--jobs")
    ap.add_argument("--compare")
    ap.add_argument("--title", default="Threads that share the machine")
    a = ap.parse_args()
    new = load(os.path.join(a.harness, "harness-new.json"))
    old = load(os.path.join(a.harness, f"harness-{a.ref}.json")) if a.ref else None
    c = new["context"]
    print(f"# {a.title}: {c['date'][:10]}, {c['host']}, {c['cores']} cores\n")
    print("Application figures, measured through the installed library by `bench/harness` "
          f"({c['points']:,} points; `bash scripts/bench_harness.sh" + (f" --ref {a.ref}" if a.ref else "") +
          "`), two `mbi run` jobs at once (`scripts/bench_jobs.sh`) and the isolated stages of "
          "the old and the new build alternating (`scripts/bench_compare.py`), one after the "
          "other on a quiet machine; this page by `scripts/bench_threads_report.py`.\n")
    print("## Targets\n")
    harness_table(new, old, a.ref)
    if a.jobs:
        jobs = load(a.jobs)
        bins = list(dict.fromkeys(r["binary"] for r in jobs["runs"]))
        print(f"\nTwo `mbi run {jobs['scene']} {jobs['args']} --frames {jobs['frames']}` at once, separate "
              f"folders ({len(jobs['runs']) // len(bins)} rounds, medians; `{jobs['command']}`):\n")
        print("| build | one alone | slower of two at once | ratio (bound 2.2) |")
        print("|---|---|---|---|")
        for b in bins:
            al, sl, r = jobs_ratio(jobs, b)
            print(f"| `{b}` | {fmt(al)} s | {fmt(sl)} s | {fmt(r)}x |")
    if a.compare:
        cmp_ = load(a.compare)
        print(f"\nIsolated stages, quiet, old and new build alternating ({cmp_['rounds']} rounds, medians; "
              f"`{cmp_['command']}`):\n")
        print("| benchmark | old, ms | new, ms | new / old |")
        print("|---|---|---|---|")
        for r in cmp_["rows"]:
            print(f"| {r['name'].split('/min_time')[0].split('/iterations')[0]} | {fmt(r['old_ms'], 3)} | "
                  f"{fmt(r['new_ms'], 3)} | {fmt(r['ratio'])} |")
    print("\n## Every stage beside a load (means)\n")
    print("Loads: `thread`, a thread of the process spinning on arithmetic; `process`, another process "
          "doing the same; `numpy-like` / `torch-like`, a pool of the interpreter's kind beside mbi's "
          "(bench/harness/loads.cpp).\n")
    loads_table(new, old, a.ref)
    return 0


if __name__ == "__main__":
    sys.exit(main())
