#!/usr/bin/env bash
# Runs every shipped scene (all frames) and `mbi deform --example twist-bar` (both methods) with
# the given mbi executable into OUT, for comparing two builds with scripts/compare-outputs.py;
# arguments after OUT go to every `mbi run` (e.g. --gpu off: the CPU path alone, as comparisons of
# the frame path want):
#   bash scripts/capture-outputs.sh old/mbi /tmp/before --gpu off
#   bash scripts/capture-outputs.sh build/release/mbi /tmp/after --gpu off
#   python3 scripts/compare-outputs.py /tmp/before /tmp/after
set -euo pipefail
MBI=$(realpath "$1"); OUT=$2
shift 2
cd "$(dirname "$0")/.."
mkdir -p "$OUT"
for s in scenes/*.toml; do
  name=$(basename "$s" .toml)
  rc=0
  "$MBI" run "$s" --out "$OUT/$name" --force --quiet "$@" > "$OUT/$name.stdout" 2> "$OUT/$name.stderr" || rc=$?
  echo "$name: exit $rc"
done
"$MBI" deform --example twist-bar --out "$OUT/deform-example.obj" --stats "$OUT/deform-example.json" > "$OUT/deform-example.stdout"
"$MBI" deform --example twist-bar --method bi --out "$OUT/deform-example-bi.obj" --stats "$OUT/deform-example-bi.json" > /dev/null
echo "deform: done"
