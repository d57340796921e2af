#!/usr/bin/env python3
"""Markdown report with PNG plots from mbi-bench's Google Benchmark JSON (scripts/bench.sh).

    bench_report.py RESULT.json [--machine] [--wall-s S]

--machine records this machine (CPU model, cores, memory, commit) into the JSON's context first
(bench.sh does it right after the run), so that a JSON file carries its own description.
Writes RESULT.md beside the JSON and RESULT-<plot>.png. Exit status 1 when a benchmark failed
for a reason other than "no OpenGL", "MBI_MODELS_DIR is not set" or a float kernel this CPU cannot
run (the report is still written).
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys

ALLOWED_SKIPS = ("no OpenGL", "MBI_MODELS_DIR is not set", "this CPU cannot run the")

# The paper's Table 1 (Huang et al. 2008), ms.
PAPER = {
    "bunny": dict(model="Bunny", dense=35947, control=103, fact=9.8, solve=4.0, cpu=17.0, gpu=3.3),
    "large": dict(model="Bugman", dense=264000, control=450, fact=45.3, solve=14.0, cpu=120.0, gpu=16.3),
}
# VegaFEM's corotational linear FEM step on this kind of machine (bench/bench_sim.cpp), ms.
VEGA_STEP = {1: (1311, 10.6), 2: (5125, 54.9)}


# ------------------------------------------------------------------------------------ machine
def read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return ""


def machine_facts(repo):
    cpuinfo = read("/proc/cpuinfo")
    cpu = re.search(r"^model name\s*:\s*(.*)$", cpuinfo, re.M)
    mem = re.search(r"^MemTotal:\s*(\d+) kB", read("/proc/meminfo"), re.M)

    def git(*args):
        try:
            return subprocess.run(["git", "-C", repo, *args], capture_output=True, text=True,
                                  check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            return "unknown"

    # the run's own outputs (bench/results) do not count as local changes
    dirty = git("status", "--porcelain", "--untracked-files=no", "--", ".", ":(exclude)bench/results")
    return {
        "cpu_model": cpu.group(1).strip() if cpu else "unknown",
        "cores": os.cpu_count(),
        "memory_gib": round(int(mem.group(1)) / 1048576, 1) if mem else None,
        "commit": git("rev-parse", "HEAD"),
        "commit_dirty": bool(dirty) and dirty != "unknown",
        "branch": git("rev-parse", "--abbrev-ref", "HEAD"),
        "kernel": os.uname().release,
        "cpu_simd": " ".join(f for f in ("avx2", "fma", "avx512f", "avx512dq", "avx512vl")
                             if re.search(r"^flags\s*:.*\b" + f + r"\b", cpuinfo, re.M)),
        "cpu_family_model": cpu_family_model(cpuinfo),
        "caches_getconf": caches_getconf(),
    }


def caches_getconf():
    """The data caches as getconf reports them ('L1 data 48 KiB, L2 1024 KiB, ...'), for machines
    whose sysfs has no cache entries (Google Benchmark then records none)."""
    out = []
    for name, label in (("LEVEL1_DCACHE_SIZE", "L1 data"), ("LEVEL2_CACHE_SIZE", "L2"), ("LEVEL3_CACHE_SIZE", "L3")):
        try:
            v = int(subprocess.run(["getconf", name], capture_output=True, text=True, check=True).stdout.strip() or 0)
        except (OSError, ValueError, subprocess.CalledProcessError):
            v = 0
        if v > 0:
            out.append(f"{label} {v // 1024} KiB")
    return ", ".join(out) + " (getconf)" if out else ""


def cpu_family_model(info):
    """'family 26, model 2' from /proc/cpuinfo's text (x86), or ''."""
    fam = re.search(r"^cpu family\s*:\s*(\d+)", info, re.M)
    mod = re.search(r"^model\s*:\s*(\d+)", info, re.M)
    return f"family {fam.group(1)}, model {mod.group(1)}" if fam and mod else ""


# ------------------------------------------------------------------------------------ parsing
def parse_name(name):
    """'BM_Eval/points:35000/control:100/min_time:0.010/real_time' -> ('BM_Eval', {...}, [...])"""
    parts = name.split("/")
    kv, plain = {}, []
    for p in parts[1:]:
        if p in ("real_time",) or p.startswith(("min_time:", "iterations:", "repeats:")):
            continue
        if ":" in p:
            k, v = p.split(":", 1)
            try:
                kv[k] = int(v)
            except ValueError:
                kv[k] = v
        else:
            plain.append(p)
    return parts[0], kv, plain


def ms(b):
    """Time per iteration in ms."""
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b.get("time_unit", "ns")]
    return b["real_time"] * scale


class Results:
    def __init__(self, data):
        self.data = data
        self.rows = []
        # with repetitions (scripts/bench.sh runs 3, randomly interleaved) the medians stand for
        # each benchmark; a benchmark that failed has no aggregate and keeps its error row
        benches = data["benchmarks"]
        with_median = {b.get("run_name") for b in benches if b.get("aggregate_name") == "median"}
        self.repetitions = max((int(b.get("repetitions", 1)) for b in benches), default=1)
        for b in benches:
            if b.get("run_type", "iteration") == "aggregate":
                if b.get("aggregate_name") != "median":
                    continue
            elif b.get("run_name") in with_median:
                continue
            fam, kv, plain = parse_name(b.get("run_name") or b["name"])
            self.rows.append(dict(fam=fam, kv=kv, plain=plain, b=b))

    def find(self, fam, plain=None, **kv):
        for r in self.rows:
            if r["fam"] != fam or r["b"].get("error_occurred"):
                continue
            if plain is not None and r["plain"] != plain:
                continue
            if all(r["kv"].get(k) == v for k, v in kv.items()):
                return r["b"]
        return None

    def all(self, fam):
        return [r for r in self.rows if r["fam"] == fam and not r["b"].get("error_occurred")]

    def errors(self):
        # a benchmark that failed in every repetition has no median: its rows once each
        seen, out = set(), []
        for r in self.rows:
            if not r["b"].get("error_occurred"):
                continue
            name = r["b"].get("run_name") or r["b"]["name"]
            if name not in seen:
                seen.add(name)
                out.append((name, r["b"].get("error_message", "")))
        return out


# ------------------------------------------------------------------------------------ format
def f_ms(x):
    if x is None:
        return "n/a"
    if x >= 100:
        return f"{x:,.0f} ms"
    if x >= 1:
        return f"{x:.3g} ms"
    return f"{x * 1000:.3g} us"


def f_num(x, digits=3):
    return "n/a" if x is None else f"{x:.{digits}g}"


def gbs(b):
    return b.get("bytes_per_second", 0) / 1e9 if b else None


def mpts(b):
    return b.get("items_per_second", 0) / 1e6 if b else None


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def loglog_fit(xs, ys):
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in pts)
    k = sxy / sxx
    return k, math.exp(my - k * mx)


# ------------------------------------------------------------------------------------ report
def target_row(name, measured, goal, met, how):
    return [name, measured, goal, "n/a" if met is None else ("**yes**" if met else "**no**"), how]


def eval_targets(R, nthreads):
    """Target (1): evaluation of 1M points against the peers, the triad, 1 thread, BI and normals."""
    ev = lambda **kv: R.find("BM_Eval", **kv)
    P = 1000000
    triad1, triadN = R.find("BM_Triad", threads=1), R.find("BM_Triad", threads=0)
    ours = ev(points=P, control=450, mbi=1, threads=0, double=0, normals=0)
    ours1 = ev(points=P, control=450, mbi=1, threads=1, double=0, normals=0)
    ours_bi = ev(points=P, control=450, mbi=0, threads=0, double=0, normals=0)
    ours_n = ev(points=P, control=450, mbi=1, threads=0, double=0, normals=1)
    vega = R.find("BM_PeerVegaLoop", points=P, control=450)
    rows = []
    target = lambda *a: rows.append(target_row(*a))
    if ours and vega:
        r = ms(vega) / ms(ours)
        target("(1) 1M points, float positions, all threads vs the peers' plain double BI loop (1 thread)",
               (f"{r:.2f}x faster" if r >= 1 else f"{1 / r:.2f}x slower") + f" ({f_ms(ms(ours))} vs {f_ms(ms(vega))})", ">= 2x", r >= 2,
               "BM_Eval modified-BI vs BM_PeerVegaLoop, 448 control vertices")
    else:
        target("(1) 1M float positions vs the plain double BI loop", "not measured", ">= 2x", None, "full run only")
    if ours and triadN:
        fr = gbs(ours) / gbs(triadN)
        target("(1) bandwidth: fraction of the triad (all threads) for its bytes",
               f"{100 * fr:.0f}% ({gbs(ours):.1f} of {gbs(triadN):.1f} GB/s, {ours['bytes_per_eval'] / P:.0f} B a point)",
               ">= 70%", fr >= 0.7, "bytes counted as in 'What is counted'")
    else:
        target("(1) bandwidth: fraction of the triad", "not measured", ">= 70%", None, "full run only")
    if ours and ours1 and triad1 and triadN:
        s = ms(ours1) / ms(ours)
        ts = gbs(triadN) / gbs(triad1)
        target(f"(1) threads scale: 1 -> {nthreads} threads",
               f"{s:.2f}x (triad: {ts:.2f}x)", f">= 80% of the triad's scaling ({0.8 * ts:.2f}x)",
               s >= 0.8 * ts, "our reading of 'threads scale': memory-bound work cannot beat the triad")
    else:
        target("(1) threads scale", "not measured", "", None, "full run only")
    if ours and ours_bi:
        r = ms(ours) / ms(ours_bi)
        target("(1) modified-BI / BI through the same kernel", f"{r:.2f}x", "<= 1.3x", r <= 1.3,
               "1M float positions, all threads")
    else:
        target("(1) modified-BI / BI", "not measured", "<= 1.3x", None, "full run only")
    if ours and ours_n:
        r = ms(ours_n) / ms(ours)
        target("(1) positions + normals / positions alone", f"{r:.2f}x", "<= 2x", r <= 2,
               "1M float, modified-BI, all threads")
    else:
        target("(1) positions + normals / positions", "not measured", "<= 2x", None, "full run only")
    return rows


def scale_targets(R):
    """Targets (2) to (5): solve, precompute, embedding and the simulator step at given sizes."""
    rows = []
    target = lambda *a: rows.append(target_row(*a))
    for c, goal in ((450, 0.1), (1300, 2.0), (10000, 30.0)):
        b = R.find("BM_ScaleSolve", control=c)
        v = ms(b) if b else None
        how = "BM_ScaleSolve, box cage" + (f": {b.get('label')}" if b and b.get("label") else "")
        if b and "dense_operator" in b:
            how += ", dense operator" if b["dense_operator"] else ", sparse sweeps"
        target(f"(2) per-frame solve at ~{c:,} control vertices", f_ms(v), f"<= {f_ms(goal)}",
               None if v is None else v <= goal, how)
    for c, goal in ((1300, 150.0), (10000, 5000.0)):
        b = R.find("BM_ScalePrecompute", control=c, cholmod=1) or R.find("BM_ScalePrecompute", control=c)
        v = ms(b) if b else None
        mem = f", {b['memory_mb']:,.0f} MB kept" if b and "memory_mb" in b else ""
        target(f"(3) precompute at ~{c:,} control vertices", (f_ms(v) + mem) if v else "not measured",
               f"<= {f_ms(goal)}", None if v is None else v <= goal,
               "BM_ScalePrecompute: assembly + " + (b.get("label") or "Eigen SimplicialLLT" if b else "?"))
    b = R.find("BM_Embed", points=1000000, tets=5000)
    target("(4) embedding 1M points into 5,082 tetrahedra", f_ms(ms(b)) if b else "not measured", "< 1 s",
           None if not b else ms(b) < 1000, "BM_Embed")
    for mesh, (vtets, vms) in VEGA_STEP.items():
        b = R.find("BM_SimStep", mesh=mesh, solver=2, tol=8)
        goal = vms / 5
        target(f"(5) simulator step at ~{vtets:,} tetrahedra",
               f_ms(ms(b)) + f" ({vms / ms(b):.1f}x VegaFEM's {vms} ms)" if b else "not measured",
               f"<= {goal:.2f} ms (5x faster)", None if not b else ms(b) <= goal,
               "default solver at this size (PCG, tol 1e-8, as LinearSolver::Auto picks)")
    return rows


def targets(R, nthreads):
    """Rows [name, measured, goal, met, how] of the speed targets, from one run."""
    return eval_targets(R, nthreads) + scale_targets(R)


class Run:
    """What several sections of one report share."""

    def __init__(self, data, json_path):
        self.R = R = Results(data)
        self.ctx = data["context"]
        self.facts = self.ctx.get("mbi", {})
        self.json_name = os.path.basename(json_path)
        self.stem = os.path.basename(os.path.splitext(json_path)[0])
        self.quick = any(r["fam"] == "BM_Eval" for r in R.rows) and not R.find("BM_Eval", points=1000000)
        gpu_rows = R.all("BM_GpuEvaluate") + R.all("BM_Table1Gpu")
        self.renderer = gpu_rows[0]["b"].get("label", "") if gpu_rows else None
        self.triad1, self.triadN = R.find("BM_Triad", threads=1), R.find("BM_Triad", threads=0)
        self.nthreads = int(self.triadN["threads"]) if self.triadN else (self.facts.get("cores") or 1)
        self.sizes = sorted({r["kv"]["points"] for r in R.all("BM_Eval")})


def caches_text(ctx):
    caches = (f"L{c['level']} {c['type'].lower()} {c['size'] // 1024} KiB"
              + (f" (x{ctx['num_cpus'] // c['num_sharing']})" if c.get('num_sharing') else "")
              for c in ctx.get("caches", []))
    return ", ".join(caches)


def machine_table(run, wall_s):
    ctx, facts = run.ctx, run.facts
    float_rows = [r for r in run.R.all("BM_Eval") if not r["kv"].get("double")]
    kernel = float_rows[0]["b"].get("label") if float_rows else None
    if facts.get("cpu_simd"):
        kernel = (kernel or "?") + f" (CPU flags: {facts['cpu_simd']})"
    return table(["", ""], [
        ["date", ctx.get("date", "?")],
        ["host", ctx.get("host_name", "?")],
        ["CPU", f"{facts.get('cpu_model', '?')}"
                + (f" ({facts['cpu_family_model']})" if facts.get("cpu_family_model") else "")
                + f", {ctx.get('num_cpus', '?')} logical cores at {ctx.get('mhz_per_cpu', '?')} MHz"],
        ["caches", caches_text(ctx) or facts.get("caches_getconf", "?")],
        ["memory", f"{facts.get('memory_gib', '?')} GiB"],
        ["float kernel (picked at run time)", kernel or "?"],
        ["OpenGL renderer", run.renderer or "none (GPU rows skipped)"],
        ["commit", f"`{facts.get('commit', '?')}`" + (" (with local changes)" if facts.get("commit_dirty") else "")
                   + f" on `{facts.get('branch', '?')}`"],
        ["load average at start", ", ".join(f"{x:.2f}" for x in ctx.get("load_avg", []))],
        ["wall time of the run", f"{wall_s:.0f} s" if wall_s else "?"],
    ])


def header_section(run, wall_s):
    """The title, the machine and how the times were taken."""
    yield f"# mbi benchmarks: {run.stem}" + (" (quick mode)" if run.quick else "")
    yield ""
    yield ("Written by `scripts/bench_report.py` from the Google Benchmark JSON of `mbi-bench` "
           f"([{run.json_name}]({run.json_name})), "
           "run by `scripts/bench.sh" + (" --quick" if run.quick else "") + "`.")
    yield ""
    yield machine_table(run, wall_s)
    yield ""
    if run.R.repetitions > 1:
        how = (f"each the median of {run.R.repetitions} repetitions run in random order among all the others "
               "(a slow spell of this shared machine then falls on different benchmarks, not all on one)")
    else:
        how = "one measurement each (no repetitions)"
    yield (f"Times are wall-clock per iteration (Google Benchmark, `UseRealTime`), {how}. Google Benchmark "
           f"reports its own library as a `{run.ctx.get('library_build_type', '?')}` build; mbi itself is built "
           "with the `release` preset.")
    yield ""


def baseline_where(run, baseline):
    """Where the baseline ran, against this run's machine: whether its times compare."""
    ctx, bc = run.ctx, baseline["context"]
    bctx = bc.get("mbi", {})
    same = (bctx.get("cpu_family_model") and bctx.get("cpu_family_model") == run.facts.get("cpu_family_model")
            and bc.get("mhz_per_cpu") == ctx.get("mhz_per_cpu"))
    if same:
        return "same machine"
    known = bool(bctx.get("cpu_family_model"))  # older reports did not record the CPU's family
    caches = ", ".join(f"L{c['level']} {c['type'].lower()} {c['size'] // 1024} KiB" for c in bc.get("caches", [])
                       if c.get("level") in (1, 2) and c.get("type") != "Instruction")
    return (f"measured on {bctx.get('cpu_model', 'a CPU it did not record')}"
            + (f" ({bctx['cpu_family_model']})" if bctx.get("cpu_family_model") else "")
            + f", {bc.get('num_cpus', '?')} cores at {bc.get('mhz_per_cpu', '?')} MHz, "
            + (caches or "caches not recorded")
            + (": not this machine, so compare its ratios, not its times" if known or
               bc.get("mhz_per_cpu") != ctx.get("mhz_per_cpu") else
               ": whether on this machine is not recorded, so compare its ratios, not its times"))


def targets_section(run, baseline, baseline_path):
    """The speed targets, with a 'before' column from the baseline run when there is one."""
    rows = targets(run.R, run.nthreads)
    if baseline is not None:
        before = targets(Results(baseline), run.nthreads)
        rows = [r[:1] + [b[1]] + r[1:] for r, b in zip(rows, before)]
    yield "## Speed targets"
    yield ""
    yield "Each measured in this run; ratios are between benchmarks of this same run."
    if baseline is not None:
        bctx = baseline["context"].get("mbi", {})
        name = os.path.basename(baseline_path)
        yield (f"'before' = the same rows from [{name}]({name}), "
               f"commit `{bctx.get('commit', baseline['context'].get('mbi_commit', '?'))}`, "
               f"{baseline_where(run, baseline)}; its own ratios come from its own run.")
    yield ""
    yield table(["target"] + (["before"] if baseline is not None else []) + ["measured", "target", "met?", "how"],
                rows)
    yield ""


def table1_row(R, key, label):
    """One model's row of the paper's Table 1, ours beside the paper's; None when neither has it."""
    pre = R.find("BM_Table1Precompute", plain=[key])
    sol = R.find("BM_Table1Solve", plain=[key])
    cpu = R.find("BM_Table1Cpu", plain=[key], threads=0)
    cpu1 = R.find("BM_Table1Cpu", plain=[key], threads=1)
    gpu = R.find("BM_Table1Gpu", plain=[key])
    p = PAPER.get(key)
    any_b = pre or sol or cpu
    if not any_b and not p:
        return None
    pc = lambda k: f"{p[k]} ms" if p else ""
    return [
        label + (f" / {p['model']}" if p else ""),
        f"{int(any_b['dense']):,}" if any_b else "skipped",
        f"{int(any_b['tets']):,}" if any_b else "",
        f"{int(any_b['control'])}" + (f" / {p['control']}" if p else "") if any_b else (f"/ {p['control']}" if p else ""),
        f_ms(ms(pre)) if pre else "n/a", pc("fact"),
        f_ms(ms(sol)) if sol else "n/a", pc("solve"),
        (f_ms(ms(cpu)) + (f" ({f_ms(ms(cpu1))})" if cpu1 else "")) if cpu else "n/a", pc("cpu"),
        f_ms(ms(gpu)) if gpu else "n/a", pc("gpu"),
    ]


def table1_section(run):
    yield "## The paper's Table 1"
    yield ""
    yield ("Factorization = the whole `interp::ModifiedBI` constructor (assembly, beta, gauge, and the "
           "factorization: CHOLMOD's supernodal Cholesky when the build has it, else Eigen's SimplicialLLT); "
           "solve = all M_i for one pose; CPU interpolation = our kernel (`interp::FastEvaluator`, as the "
           "pipeline's float CPU evaluator runs it), float positions, "
           f"all {run.nthreads} threads (1 thread in brackets); GPU interpolation = the transform-feedback evaluator, "
           "per-frame upload included, on the renderer above. The paper's figures (2008 hardware) are in "
           "the columns beside ours; our `large` shape stands for the paper's Bugman.")
    yield ""
    rows = [table1_row(run.R, key, label) for key, label in
            (("bar", "Bar (paper Fig. 1)"), ("bunny", "Stanford bunny"), ("large", "large: bumpy sphere"))]
    yield table(["model", "dense vertices", "tetrahedra", "control vertices (ours / paper)", "factorization",
                 "paper", "solve", "paper", "CPU interpolation", "paper", "GPU interpolation", "paper"],
                [r for r in rows if r is not None])
    yield ""
    if run.R.find("BM_Table1Precompute", plain=["bunny"]) is None:
        yield "The bunny row needs `MBI_MODELS_DIR` (the scanned models); it was not set for this run."
        yield ""


def throughput_section(run):
    """Million points a second of our kernel, the peers and the GPU, by point count."""
    R = run.R
    ev = lambda **kv: R.find("BM_Eval", **kv)
    yield "## Interpolation throughput"
    yield ""
    yield f"![throughput]({run.stem}-throughput.png)"
    yield ""
    hdr = ["implementation"] + [f"{p:,} points" for p in run.sizes]
    lines = [
        ("ours, modified-BI, float, all threads", lambda p: ev(points=p, control=450, mbi=1, threads=0, double=0, normals=0)),
        ("ours, modified-BI, float, 1 thread", lambda p: ev(points=p, control=450, mbi=1, threads=1, double=0, normals=0)),
        ("ours, BI, double, 1 thread", lambda p: ev(points=p, control=450, mbi=0, threads=1, double=1, normals=0)),
        ("peer: Eigen sparse W X, BI, double, 1 thread", lambda p: R.find("BM_PeerEigenSparse", points=p, control=450)),
        ("peer: VegaFEM-style loop, BI, double, 1 thread", lambda p: R.find("BM_PeerVegaLoop", points=p, control=450)),
        ("peer: modified-BI formula loop, double, 1 thread", lambda p: R.find("BM_PeerMbiFormula", points=p, control=450)),
        ("GPU evaluator, upload included (" + (run.renderer or "no GL") + ")", lambda p: R.find("BM_GpuEvaluate", points=p)),
    ]
    yield "Million points per second, 448 control vertices (time per evaluation in brackets):"
    yield ""
    yield table(hdr, [[name] + [(f"{mpts(b) if mpts(b) else p / ms(b) / 1e3:.0f} ({f_ms(ms(b))})" if b else "n/a")
                                for p, b in ((p, fn(p)) for p in run.sizes)] for name, fn in lines])
    yield ""


def configs_section(run):
    """Every configuration of our kernel, folded away."""
    yield ("Every configuration of our kernel (GB/s = the counted bytes over the time; % triad = of the "
           "triad bandwidth with the same number of threads):")
    yield ""
    full = []
    for r in run.R.all("BM_Eval"):
        k, b = r["kv"], r["b"]
        tri = run.triad1 if k["threads"] == 1 else run.triadN
        full.append([f"{k['points']:,}", int(b["control"]), "modified-BI" if k["mbi"] else "BI",
                     int(b["threads"]), "double" if k["double"] else "float",
                     "pos + normals" if k["normals"] else "pos", f_ms(ms(b)), f"{mpts(b):.0f}",
                     f"{b['bytes_per_eval'] / k['points']:.1f}", f"{gbs(b):.2f}",
                     f"{100 * gbs(b) / gbs(tri):.0f}%" if tri else "n/a"])
    yield "<details><summary>all " + str(len(full)) + " configurations</summary>"
    yield ""
    yield table(["points", "control", "method", "threads", "scalar", "outputs", "time", "Mpoints/s",
                 "B/point", "GB/s", "% triad"], full)
    yield ""
    yield "</details>"
    yield ""


def peers_section(run):
    peers = []
    for fam, what in (("BM_PeerEigenSparse", "Eigen::SparseMatrix<double, RowMajor> (4 nonzeros a row) x n x 3 RowMajor"),
                      ("BM_PeerVegaLoop", "per-point loop over 4 stored weights and vertex indices (VegaFEM's interpolate)"),
                      ("BM_PeerMbiFormula", "per-point loop over x(u) = sum phi_i (x_i + M_i (u - u_i))")):
        for r in run.R.all(fam):
            b = r["b"]
            peers.append([fam.replace("BM_Peer", ""), what, f"{r['kv']['points']:,}", r["kv"]["control"],
                          f_ms(ms(b)), f"{mpts(b):.0f}", f"{gbs(b):.2f}",
                          f"{100 * gbs(b) / gbs(run.triad1):.0f}%" if run.triad1 else "n/a",
                          f"{b.get('max_diff_vs_kernel', float('nan')):.1e}"])
    yield "Peers (double, 1 thread; each checked against our kernel's result, largest difference in the last column):"
    yield ""
    yield table(["peer", "what", "points", "control", "time", "Mpoints/s", "GB/s", "% triad (1 thread)",
                 "max diff"], peers)
    yield ""


def kernel_rows(run):
    """Rows [kernel, threads, positions, positions + normals, normals ratio] of BM_EvalKernels."""
    names = {1: "AVX-512", 2: "AVX2", 3: "portable"}
    triad1, triadN = run.triad1, run.triadN
    rows = []
    for simd in (1, 2, 3):
        for threads in (1, 0):
            pos = run.R.find("BM_EvalKernels", simd=simd, threads=threads, normals=0)
            nrm = run.R.find("BM_EvalKernels", simd=simd, threads=threads, normals=1)
            if not pos and not nrm:
                continue
            used = int((pos or nrm).get("threads_used", (pos or nrm)["threads"]))
            # the triad on as many threads as ran (none measured for other counts)
            tri = triad1 if used == 1 else triadN if triadN and used == int(triadN["threads"]) else None
            cell = lambda b: (f"{f_ms(ms(b))} ({100 * gbs(b) / gbs(tri):.0f}%)" if tri and gbs(tri) > 0
                              else f_ms(ms(b))) if b else "n/a"
            rows.append([names[simd], "1" if threads == 1 else f"all ({used} used)",
                         cell(pos), cell(nrm), f"{ms(nrm) / ms(pos):.2f}x" if pos and nrm else "n/a"])
    return rows


def kernels_section(run):
    """The float kernels side by side, when the run measured them."""
    kern = run.R.all("BM_EvalKernels")
    if not kern:
        return
    yield (f"The float kernels side by side (`BM_EvalKernels`, `interp::Simd`): {int(kern[0]['b']['points']):,} "
           f"random points, modified-BI, 448 control vertices; % triad = of the triad on as many threads as the "
           "kernel used (fewer than 65,536 points run on one); normals ratio = positions + "
           "normals over positions alone, same kernel and threads:")
    yield ""
    yield table(["kernel", "threads", "positions (% triad)", "positions + normals (% triad)", "normals ratio"],
                kernel_rows(run))
    yield ""
    skipped = sorted({m for n, m in run.R.errors() if n.startswith("BM_EvalKernels")})
    if skipped:
        yield "Not run: " + "; ".join(skipped) + "."
        yield ""


def triad_section(run):
    yield "### The machine's limit"
    yield ""
    yield table(["STREAM-style triad a = b + s c", "GB/s", "array size"],
                [[f"{int(b['threads'])} thread(s)", f"{gbs(b):.1f}", f"3 x {b['bytes_per_eval'] / 3 / 2**20:.0f} MiB"]
                 for b in (run.triad1, run.triadN) if b])
    yield ""


def gpu_section(run):
    """CPU against GPU evaluation of one frame, by point count."""
    yield "## CPU vs GPU evaluation (the design card's benchmark)"
    yield ""
    yield ("One modified-BI frame of p random points in the 448-vertex box cage: the GPU evaluator with "
           "the per-frame upload of the Bezier points and without it (the pass alone), against the frame "
           "pipeline's CPU evaluator (float, all threads).")
    yield ""
    g = []
    for p in run.sizes:
        gb, cb = run.R.find("BM_GpuEvaluate", points=p), run.R.find("BM_GpuCpuEvaluate", points=p)
        g.append([f"{p:,}", f_ms(ms(gb)) if gb else "skipped", f_ms(gb["upload_ms"]) if gb else "",
                  f_ms(gb["pass_ms"]) if gb else "", f_ms(ms(cb)) if cb else "n/a",
                  f"{ms(gb) / ms(cb):.1f}x" if gb and cb else ""])
    yield table(["points", "GPU, upload included", "upload", "GPU pass alone", "CPU (float, all threads)",
                 "GPU / CPU time"], g)
    yield ""
    if run.renderer and "llvmpipe" in run.renderer:
        yield (f"The renderer is `{run.renderer}`: Mesa's software rasteriser runs the shader on the same CPU "
               "cores, so these GPU rows check that the path works; they are not GPU speed.")
        yield ""


def scaling_rows(pre_all, sol):
    """Rows [control, Eigen precompute, CHOLMOD precompute, solve, solve path] by control count."""
    rows = []
    for c in sorted({r["b"]["control"] for r in pre_all} | {x[0] for x in sol}):
        e = next((r["b"] for r in pre_all if r["b"]["control"] == c and r["kv"].get("cholmod", 0) == 0), None)
        ch = next((r["b"] for r in pre_all if r["b"]["control"] == c and r["kv"].get("cholmod") == 1), None)
        s_ = next((x for x in sol if x[0] == c), None)
        cell = lambda b: (f_ms(ms(b)) + (f" ({b['factor_nnz'] / 1e6:.2f}M nnz, {b['memory_mb']:,.0f} MB)" if "factor_nnz" in b else "")) if b else "n/a"
        rows.append([f"{int(c):,}", cell(e), cell(ch), f_ms(s_[1]) if s_ else "n/a",
                     ("dense operator" if s_[2] else "sparse sweeps") if s_ else ""])
    return rows


def scaling_section(run):
    """Precompute and solve against the control-vertex count, with fitted growth."""
    yield "## Precompute and solve against the control-vertex count"
    yield ""
    yield f"![scaling]({run.stem}-scaling.png)"
    yield ""
    # the precompute the solve runs on: CHOLMOD's when the run has it (Factorization::Automatic)
    pre_all = run.R.all("BM_ScalePrecompute")
    have_chol = any(r["kv"].get("cholmod") == 1 for r in pre_all)
    pre = [(r["b"]["control"], ms(r["b"])) for r in pre_all if r["kv"].get("cholmod", 0) == (1 if have_chol else 0)]
    sol = [(r["b"]["control"], ms(r["b"]), r["b"].get("dense_operator")) for r in run.R.all("BM_ScaleSolve")]
    fp = loglog_fit([x for x, _ in pre], [y for _, y in pre])
    fs = loglog_fit([x for x, _, _ in sol], [y for _, y, _ in sol])
    yield table(["control vertices", "precompute, Eigen SimplicialLLT (factor nonzeros, memory kept)",
                 "precompute, CHOLMOD supernodal", "per-frame solve", "solve path"], scaling_rows(pre_all, sol))
    yield ""
    if fp and fs:
        yield (f"Fitted growth (least squares on log t against log n over all sizes): precompute ~ "
               f"n^{fp[0]:.2f}, solve ~ n^{fs[0]:.2f}. The solve path is the automatic one: below a "
               "threshold (interp/src/method/modified_bi.cpp) the precompute also forms the dense operator "
               "-H_mm^-1 H_mx, which is why it costs more at 448 vertices relative to its neighbours, "
               "and the solve is one dense product (threaded, AVX2); above it, the solve sweeps the "
               "Cholesky factor once forward and once back for all 3 components together.")
        yield ""


def embed_section(run):
    yield "## Embedding"
    yield ""
    yield ("Random points inside box cages of unit cells (5x5x3 and 11x11x7 cells, 6 tetrahedra each), "
           "located with the uniform grid of `interp::embed`.")
    yield ""
    yield table(["points", "tetrahedra", "time", "Mpoints/s"],
                [[f"{r['kv']['points']:,}", f"{int(r['b']['tets']):,}", f_ms(ms(r["b"])), f"{mpts(r['b']):.2f}"]
                 for r in run.R.all("BM_Embed")])
    yield ""


def sim_section(run):
    yield "## Simulator step"
    yield ""
    yield ("Co-rotational linear FEM, implicit Euler, one Newton iteration, dt = 1/60 s (bench/bench_sim.cpp). "
           "VegaFEM on this kind of machine: 10.6 ms at 1,311 and 54.9 ms at 5,125 tetrahedra.")
    yield ""
    yield table(["tetrahedra", "solver", "time per step", "assembly", "linear solve", "PCG iterations"],
                [[f"{int(r['b']['tets']):,}",
                  "LDLT" if r["kv"]["solver"] == 1 else f"PCG, tol 1e-{r['kv']['tol']}",
                  f_ms(ms(r["b"])), f_ms(r["b"]["assemble_ms"]), f_ms(r["b"]["solve_ms"]),
                  f"{r['b']['pcg_iters_per_step']:.0f}" if r["kv"]["solver"] == 2 else ""]
                 for r in run.R.all("BM_SimStep")])
    yield ""


def scenes_section(run):
    yield "## End to end: one frame of each shipped scene"
    yield ""
    yield "Through the frame pipeline as `mbi run` sets it up (CPU evaluation in double), without writing files."
    yield ""
    yield table(["scene", "dense", "control", "frame", "drive", "solve", "Bezier", "evaluate"],
                [[r["plain"][0] if r["plain"] else "?", f"{int(r['b']['dense']):,}", int(r["b"]["control"]),
                  f_ms(ms(r["b"])), f_ms(r["b"]["drive_ms"]), f_ms(r["b"]["solve_ms"]),
                  f_ms(r["b"]["bezier_ms"]), f_ms(r["b"]["evaluate_ms"])] for r in run.R.all("BM_SceneFrame")])
    yield ""


def counted_section():
    """How bytes per evaluation are counted (fixed text)."""
    yield "## What is counted"
    yield ""
    yield ("Bytes per evaluation, each read or written once (the STREAM convention: the triad counts "
           "24 B per element; write-allocate traffic is counted by neither):")
    yield ""
    yield ("- **our kernel, float** (`interp::FastEvaluator`): per point the packed record (element id "
           "4 B + 3 float barycentric coordinates 12 B) and the position written (3 x 4 B): 28 B; with "
           "normals also the rest normal read and the normal written (2 x 3 x 4 B): 52 B. Per call the "
           "element Bezier points (m x 10 x 3 doubles); not counted: the per-element float coefficients "
           "written and read back once per call (m x 40 floats, m x 48 more with normals).")
    yield ("- **our kernel, double** (`interp::evaluate<double>`, the exact path): per point the element "
           "id (4 B), 4 barycentric coordinates (4 x 8 B: `Embedding` stores doubles) and the position "
           "written (3 x 8 B): 60 B; with normals also the rest normal read and the normal written "
           "(2 x 3 x 8 B): 108 B. Per call the Bezier points and, with normals, the basis gradients "
           "(m x 4 x 3 doubles).")
    yield ("- **Eigen sparse**: per row 4 values (32 B), 4 column indices (16 B), the row start (4 B), "
           "the output row (24 B); per call X.")
    yield "- **VegaFEM-style loop**: per point 4 indices (16 B), 4 weights (32 B), output (24 B); per call X."
    yield ("- **modified-BI formula loop**: per point element id (4 B), coordinates (32 B), rest point (24 B), "
           "output (24 B); per call x_i, u_i and M_i (15 doubles a vertex).")
    yield ""
    yield ("Points are uniformly random in a box cage (448 vertices, 1,764 tetrahedra; or 100 vertices, "
           "288 tetrahedra), so consecutive points fall in unrelated elements: the Bezier table "
           "(1,764 x 10 x 3 doubles = 423 KB) stays in L2, the per-point arrays stream from memory.")
    yield ""


def skipped_section(run):
    errs = run.R.errors()
    if errs:
        yield "## Skipped"
        yield ""
        yield table(["benchmark", "reason"], [[n, m] for n, m in errs])
        yield ""


def report(data, json_path, wall_s, baseline=None, baseline_path=None):
    """The Markdown report of one run, its Results and whether it was a quick run."""
    run = Run(data, json_path)
    sections = (header_section(run, wall_s), targets_section(run, baseline, baseline_path),
                table1_section(run), throughput_section(run), configs_section(run), peers_section(run),
                kernels_section(run), triad_section(run), gpu_section(run), scaling_section(run),
                embed_section(run), sim_section(run), scenes_section(run), counted_section(),
                skipped_section(run))
    return "\n".join(line for s in sections for line in s) + "\n", run.R, run.quick


# ------------------------------------------------------------------------------------ plots
def throughput_plot(R, base, plt):
    """Million points a second against the point count, ours and the peers', with the triad's limit."""
    sizes = sorted({r["kv"]["points"] for r in R.all("BM_Eval")})
    ev = lambda **kv: R.find("BM_Eval", **kv)
    triadN = R.find("BM_Triad", threads=0)
    series = [
        ("ours: modified-BI, float, all threads", "C0", "-o", lambda p: ev(points=p, control=450, mbi=1, threads=0, double=0, normals=0)),
        ("ours: modified-BI, float, 1 thread", "C0", "--o", lambda p: ev(points=p, control=450, mbi=1, threads=1, double=0, normals=0)),
        ("ours: modified-BI, double, pos + normals, all threads", "C5", "-^", lambda p: ev(points=p, control=450, mbi=1, threads=0, double=1, normals=1)),
        ("peer: Eigen sparse W X (BI, 1 thread)", "C1", "-s", lambda p: R.find("BM_PeerEigenSparse", points=p, control=450)),
        ("peer: VegaFEM-style loop (BI, 1 thread)", "C2", "-s", lambda p: R.find("BM_PeerVegaLoop", points=p, control=450)),
        ("peer: modified-BI formula loop (1 thread)", "C3", "-s", lambda p: R.find("BM_PeerMbiFormula", points=p, control=450)),
        ("GPU evaluator, upload included", "C4", "-D", lambda p: R.find("BM_GpuEvaluate", points=p)),
    ]
    fig, ax = plt.subplots(figsize=(11, 5))
    for label, color, style, fn in series:
        pts = [(p, p / ms(b) / 1e3) for p in sizes for b in [fn(p)] if b]
        if pts:
            ax.plot([x for x, _ in pts], [y for _, y in pts], style, color=color, label=label)
    b0 = ev(points=sizes[-1], control=450, mbi=1, threads=0, double=0, normals=0) if sizes else None
    if triadN and b0:
        bpp = b0["bytes_per_eval"] / sizes[-1]
        lim = gbs(triadN) * 1e9 / bpp / 1e6
        ax.axhline(lim, color="k", ls=":", label=f"triad bandwidth / {bpp:.0f} B a point (float, all threads)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("embedded points")
    ax.set_ylabel("million points per second")
    ax.set_title("Interpolation throughput, 448 control vertices")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(base + "-throughput.png", dpi=110)
    plt.close(fig)


def scaling_plot(R, base, plt):
    """Precompute and solve time against the control-vertex count, with fitted growth."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for fam, label, color in (("BM_ScalePrecompute", "precompute (assembly + factorisation)", "C0"),
                              ("BM_ScaleSolve", "per-frame solve", "C1")):
        rs = R.all(fam)
        if fam == "BM_ScalePrecompute" and any(r["kv"].get("cholmod") == 1 for r in rs):
            rs = [r for r in rs if r["kv"].get("cholmod") == 1]
            label = "precompute (assembly + CHOLMOD factorisation)"
        pts = sorted((r["b"]["control"], ms(r["b"])) for r in rs)
        if not pts:
            continue
        fit = loglog_fit([x for x, _ in pts], [y for _, y in pts])
        ax.plot([x for x, _ in pts], [y for _, y in pts], "o-", color=color,
                label=label + (f", fit ~ n^{fit[0]:.2f}" if fit else ""))
        if fit:
            xs = [pts[0][0], pts[-1][0]]
            ax.plot(xs, [fit[1] * x ** fit[0] for x in xs], ":", color=color)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("control vertices (box cages)")
    ax.set_ylabel("ms")
    ax.set_title("Modified-BI precompute and solve")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(base + "-scaling.png", dpi=110)
    plt.close(fig)


def plots(R, base):
    """RESULT-throughput.png and RESULT-scaling.png beside the report."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    throughput_plot(R, base, plt)
    scaling_plot(R, base, plt)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("json")
    ap.add_argument("--machine", action="store_true", help="record this machine into the JSON first")
    ap.add_argument("--wall-s", type=float, default=None, help="wall time of the run, recorded with --machine")
    ap.add_argument("--baseline", default=None, help="an earlier run's JSON: its target rows become a 'before' column")
    args = ap.parse_args()
    with open(args.json) as f:
        data = json.load(f)
    if args.machine:
        repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        data["context"]["mbi"] = machine_facts(repo)
        if args.wall_s is not None:
            data["context"]["mbi"]["wall_s"] = args.wall_s
        with open(args.json + ".tmp", "w") as f:
            json.dump(data, f, indent=1)
        os.replace(args.json + ".tmp", args.json)
    base = os.path.splitext(args.json)[0]
    baseline = None
    if args.baseline:
        with open(args.baseline) as f:
            baseline = json.load(f)
    md, R, _ = report(data, args.json, data["context"].get("mbi", {}).get("wall_s"), baseline, args.baseline)
    plots(R, base)
    with open(base + ".md.tmp", "w") as f:
        f.write(md)
    os.replace(base + ".md.tmp", base + ".md")
    print(f"bench_report: wrote {base}.md, {base}-throughput.png, {base}-scaling.png")
    bad = [(n, m) for n, m in R.errors() if not m.startswith(ALLOWED_SKIPS)]
    for n, m in bad:
        print(f"bench_report: error: {n}: {m}", file=sys.stderr)
    if not R.all("BM_Eval") or not R.all("BM_Triad"):
        print("bench_report: error: no interpolation or triad results", file=sys.stderr)
        return 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
