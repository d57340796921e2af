#!/usr/bin/env bash
# The two figures of mbi deform on a trajectory (docs/cli.md, "Sequences"), written to
# bench/results/<date>-<host>-sequence.md (or --out DIR):
#  1. a 200-frame PC2 trajectory of a 1,300-vertex control mesh (mbi cage) deforming the large
#     scene's 252,152-vertex model into a PC2: the sequence's wall time against one single-pose
#     `mbi deform` call + 199 x (solve + evaluate + PC2 frame write) (per frame: the sequence's
#     own STATS.json), and the 200 separate single-pose calls it replaces, side by side;
#  2. per frame, a 1M-point model into a PC2 (solve and evaluation included) against writing the
#     same bytes with a plain fwrite loop, in one mbi-bench run, same folder, no fsync
#     (BM_SequencePc2Frame, BM_SequenceFwriteFrame; median of 5).
#
#   bash scripts/bench-sequence.sh [--out DIR] [--separate N]   (N separate calls, default 200)
#
# Builds mbi and mbi-bench (release preset) unless MBI_BENCH_NO_BUILD=1; works in
# build/bench-sequence/. Run nothing else meanwhile: the numbers are only as quiet as the machine.
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/results
separate=200
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift ;;
    --separate) separate="$2"; shift ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "bench-sequence.sh: error: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [ "${MBI_BENCH_NO_BUILD:-0}" != 1 ]; then
  cmake --preset release >/dev/null
  cmake --build --preset release -j "${MBI_JOBS:-$(nproc)}" --target mbi mbi-bench
fi
python=/usr/bin/python3
[ -x "$python" ] || python=python3
root=$(pwd)
mbi=$root/build/release/mbi
work=build/bench-sequence
mkdir -p "$work" "$out"
out=$(cd "$out" && pwd)  # absolute: the work below happens in $work
cd "$work"
if [ ! -f model.ply ]; then
  "$mbi" run "$root/scenes/large.toml" --frames 1 --out run --force --quiet --gpu off >/dev/null
  cp run/mesh_0000.ply model.ply
fi
[ -f cage.node ] || "$mbi" cage model.ply -n 1300 --out cage >/dev/null
[ -f traj.pc2 ] || "$python" "$root/bench/sequence_trajectory.py" . 200
now() { date +%s.%N; }
common=(--control cage.node --mesh model.ply --force)

t0=$(now)
"$mbi" deform "${common[@]}" --deformed traj.pc2 --out dense.pc2 --stats seq.json >/dev/null
t1=$(now)
"$mbi" deform "${common[@]}" --deformed frame_0000.txt --out one.ply >/dev/null
t2=$(now)
for ((k = 0; k < separate; k++)); do
  "$mbi" deform "${common[@]}" --deformed "$(printf 'frame_%04d.txt' "$k")" --out separate.ply >/dev/null
done
t3=$(now)
"$root/build/release/mbi-bench" --benchmark_filter='BM_Sequence' --benchmark_repetitions=5 \
  --benchmark_report_aggregates_only=true --benchmark_out=bench.json --benchmark_out_format=json >/dev/null

"$python" - "$t0" "$t1" "$t2" "$t3" "$separate" "$out" <<'PY'
import json, socket, subprocess, sys, time
t0, t1, t2, t3 = map(float, sys.argv[1:5])
separate, out = int(sys.argv[5]), sys.argv[6]
seq, single, sep = t1 - t0, t2 - t1, t3 - t2
st = json.load(open("seq.json"))
per = st["timings_ms"]["deform_per_frame"] + st["timings_ms"]["write_per_frame"]
bound = single + (st["frames"] - 1) * per / 1000
rows = {b["run_name"].split("/")[0]: b["real_time"] for b in json.load(open("bench.json"))["benchmarks"]
        if b.get("aggregate_name") == "median"}
frame, fwrite = rows["BM_SequencePc2Frame"], rows["BM_SequenceFwriteFrame"]
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
host = socket.gethostname().split(".")[0]
lines = [
    "# mbi deform on a trajectory: %s, %s, commit %s" % (time.strftime("%Y-%m-%d"), host, commit), "",
    "`bash scripts/bench-sequence.sh` (release build, %d cores). Model: the large scene's bumpy sphere,"
    " %d points; control mesh: `mbi cage -n 1300` (%d vertices, %d tetrahedra); modified-BI, alpha %.3g."
    % (__import__("os").cpu_count(), st["points"], st["control_vertices"], st["elements"], st["alpha"]), "",
    "## 1. A %d-frame PC2 trajectory into a PC2" % st["frames"], "",
    "| what | time |", "|---|---|",
    "| sequence: one `mbi deform --deformed traj.pc2 --out dense.pc2` | %.2f s |" % seq,
    "| one single-pose `mbi deform` (frame 0 into a PLY) | %.2f s |" % single,
    "| per frame in the sequence: solve + evaluate %.2f ms, PC2 write %.2f ms | %.2f ms |"
    % (st["timings_ms"]["deform_per_frame"], st["timings_ms"]["write_per_frame"], per),
    "| bound: single call + %d x per frame | %.2f s |" % (st["frames"] - 1, bound),
    "| **sequence / bound** (target <= 1.2) | **%.2f** |" % (seq / bound),
    "| the %d separate single-pose calls it replaces | %.1f s (%.1fx the sequence) |" % (separate, sep, sep / seq), "",
    "## 2. Per frame, a 1M-point model into a PC2", "",
    "| what (mbi-bench, median of 5) | ms per frame |", "|---|---|",
    "| `BM_SequencePc2Frame`: solve + float kernel + PC2 append | %.2f |" % frame,
    "| `BM_SequenceFwriteFrame`: fwrite of the same 12 MB, same folder, no fsync | %.2f |" % fwrite,
    "| **ratio** (target <= 2) | **%.2f** |" % (frame / fwrite), "",
]
path = "%s/%s-%s-sequence.md" % (out, time.strftime("%Y-%m-%d"), host)
open(path, "w").write("\n".join(lines))
print("\n".join(lines))
print("bench-sequence.sh: wrote " + path)
PY
