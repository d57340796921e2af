#!/usr/bin/env bash
# Two `mbi run` jobs at once on the machine against one alone: the wall time of each.
#
#   bash scripts/bench_jobs.sh [--mbi BINARY]... [--rounds N] [--frames F] [--scene FILE]
#                              [--out FILE.json] [-- MBI RUN ARGS...]
#
#   --mbi BINARY   an mbi to measure (default build/release/mbi); several: each in turn, round
#                  after round (e.g. an old build beside the new one)
#   --rounds N     rounds (default 3); each runs every binary once alone, then two at once
#   --frames F     frames of each job (default 20)
#   --scene FILE   default scenes/large.toml
#   --out FILE     JSON with every wall time (default build/bench-jobs.json)
#   MBI RUN ARGS   more options for every job (default --gpu off)
#
# Each job writes to a folder of its own under a temporary directory (--out, --force). Prints
# per binary the median wall time alone, of the slower of two at once, and their ratio (2x is a
# fair share of 2 cores). Run nothing else meanwhile.
set -euo pipefail
cd "$(dirname "$0")/.."

bins=()
rounds=3
frames=20
scene=scenes/large.toml
out=build/bench-jobs.json
while [ $# -gt 0 ]; do
  case "$1" in
    --mbi) bins+=("$2"); shift ;;
    --rounds) rounds="$2"; shift ;;
    --frames) frames="$2"; shift ;;
    --scene) scene="$2"; shift ;;
    --out) out="$2"; shift ;;
    --) shift; break ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "bench_jobs.sh: error: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
[ ${#bins[@]} -eq 0 ] && bins=(build/release/mbi)
extra=("$@")
[ ${#extra[@]} -eq 0 ] && extra=(--gpu off)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# job BINARY OUTDIR: one run, its wall time in seconds on stdout
job() {
  local t0 t1
  t0=$(date +%s.%N)
  "$1" run "$scene" --frames "$frames" --out "$2" --force --quiet "${extra[@]}" >/dev/null
  t1=$(date +%s.%N)
  echo "$t1 - $t0" | bc
}

rows=()
for r in $(seq 1 "$rounds"); do
  for b in "${bins[@]}"; do
    alone=$(job "$b" "$tmp/alone")
    job "$b" "$tmp/a" >"$tmp/ta" &
    pa=$!
    job "$b" "$tmp/b" >"$tmp/tb" &
    pb=$!
    wait "$pa" "$pb"
    a=$(cat "$tmp/ta")
    bb=$(cat "$tmp/tb")
    echo "bench_jobs: round $r, $b: alone ${alone} s, two at once ${a} s and ${bb} s" >&2
    rows+=("{\"binary\": \"$b\", \"round\": $r, \"alone_s\": $alone, \"together_s\": [$a, $bb]}")
  done
done

{
  echo "{\"scene\": \"$scene\", \"frames\": $frames, \"args\": \"${extra[*]}\", \"cores\": $(nproc),"
  cmd="bash scripts/bench_jobs.sh"
  for b in "${bins[@]}"; do cmd="$cmd --mbi $b"; done
  echo " \"command\": \"$cmd --rounds $rounds --frames $frames --scene $scene\","
  echo " \"runs\": ["
  for i in "${!rows[@]}"; do
    sep=$([ "$i" -lt $((${#rows[@]} - 1)) ] && echo "," || true)
    echo "  ${rows[$i]}$sep"
  done
  echo " ]}"
} >"$out"

python3 - "$out" <<'EOF'
import json, statistics, sys
d = json.load(open(sys.argv[1]))
for b in dict.fromkeys(r["binary"] for r in d["runs"]):
    rs = [r for r in d["runs"] if r["binary"] == b]
    alone = statistics.median(r["alone_s"] for r in rs)
    slower = statistics.median(max(r["together_s"]) for r in rs)
    print(f"{b}: alone {alone:.2f} s, slower of two at once {slower:.2f} s: {slower / alone:.2f}x")
EOF
