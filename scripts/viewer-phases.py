#!/usr/bin/env python3
"""The viewer's frame rate and phase times for a scene, per evaluator, measured from outside.

    viewer-phases.py [--mbi build/release/mbi] [--gpu auto,on,off] [--frames 300] [--size 1280x720]
                     SCENE [-- MBI VIEW ARGS...]

--gpu -: no --gpu option (a build from before it).
Runs `mbi view SCENE --frames N --report` under Xvfb (xvfb-run) twice per evaluator, for N and
for N / 3 frames: the difference of the two wall times over the difference of the frame counts
gives the frame rate without the start-up (window, precompute). The phases are the medians of
the report's per-frame timings_ms over the longer run, its first 20 frames left out. Prints one
Markdown row per evaluator. Run nothing else meanwhile.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

PHASES = ("simulation", "solve", "interpolation", "drawing")


def run(mbi, scene, gpu, frames, size, extra, report):
    w, h = size.split("x")
    cmd = ["xvfb-run", "-a", "-s", f"-screen 0 {w}x{int(h) + 80}x24", mbi, "view", scene, "--frames", str(frames),
           "--width", w, "--height", h, "--report", report] + (["--gpu", gpu] if gpu != "-" else []) + extra
    if os.path.exists(report):
        os.remove(report)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--mbi", default="build/release/mbi")
    ap.add_argument("--gpu", default="auto,on,off")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    print(f"| scene | --gpu | evaluator | fps | " + " | ".join(f"{p}, ms" for p in PHASES) + " | sum, ms |")
    print("|---|---|---|---|" + "---|" * (len(PHASES) + 1))
    with tempfile.TemporaryDirectory() as tmp:
        report = os.path.join(tmp, "report.json")
        for gpu in a.gpu.split(","):
            short = run(a.mbi, a.scene, gpu, a.frames // 3, a.size, a.extra, report)
            long_ = run(a.mbi, a.scene, gpu, a.frames, a.size, a.extra, report)
            fps = (a.frames - a.frames // 3) / (long_ - short)
            with open(report) as f:
                frames = json.load(f)[20:]
            med = {p: statistics.median(fr["timings_ms"].get(p, 0.0) for fr in frames) for p in PHASES}
            name = frames[-1].get("evaluator", {}).get("name", "gpu")
            print(f"| {os.path.basename(a.scene)} | {gpu} | {name} | {fps:.1f} | "
                  + " | ".join(f"{med[p]:.2f}" for p in PHASES) + f" | {sum(med.values()):.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
