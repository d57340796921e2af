#!/usr/bin/env bash
# Runs mbi-harness (bench/harness: application-style benchmarks built against an INSTALLED mbi)
# against this checkout's release build and, with --ref, against the library of an earlier
# commit built the same way, one after the other in the same run:
#
#   bash scripts/bench_harness.sh [--ref REV] [--out DIR] [--rounds N] [-- HARNESS ARGS...]
#
#   --ref REV    also build REV's libraries (git archive of REV; interp, sim, pipeline only) into
#                build/harness/REV and run the harness against them first ('before')
#   --out DIR    where the JSON goes (default build/harness): DIR/harness-new.json and, with
#                --ref, DIR/harness-REV.json
#   --rounds N   run the two libraries' harnesses N times, alternating (default 1); the JSON
#                files then hold every round's rows (harness-new-1.json, ...)
#   HARNESS ARGS passed to mbi-harness (e.g. --only loaded --loads quiet,thread)
#
# Needs the release build (cmake --build --preset release). Run nothing else meanwhile.
set -euo pipefail
cd "$(dirname "$0")/.."

refs=()
out=build/harness
rounds=1
while [ $# -gt 0 ]; do
  case "$1" in
    --ref) refs+=("$2"); shift ;;
    --out) out="$2"; shift ;;
    --rounds) rounds="$2"; shift ;;
    --) shift; break ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "bench_harness.sh: error: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
mkdir -p "$out"
root=$PWD

# harness_for NAME PREFIX: configures and builds bench/harness against PREFIX into build/harness/NAME
harness_for() {
  cmake -S bench/harness -B "build/harness/$1/harness" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$2" >/dev/null
  cmake --build "build/harness/$1/harness" >/dev/null
}

cmake --install build/release --prefix "$root/build/harness/new/prefix" >/dev/null
harness_for new "$root/build/harness/new/prefix"
for ref in "${refs[@]}"; do
  dir="build/harness/$ref"
  if [ ! -f "$dir/prefix/lib/cmake/mbi/mbiConfig.cmake" ]; then
    rm -rf "$dir/src"
    mkdir -p "$dir/src"
    git archive "$ref" | tar -x -C "$dir/src"
    cmake -S "$dir/src" -B "$dir/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMBI_BUILD_APPS=OFF \
      -DMBI_BUILD_TESTS=OFF -DMBI_BUILD_BENCH=OFF >/dev/null
    cmake --build "$dir/build" >/dev/null
    cmake --install "$dir/build" --prefix "$root/$dir/prefix" >/dev/null
  fi
  harness_for "$ref" "$root/$dir/prefix"
done

for r in $(seq 1 "$rounds"); do
  suffix=$([ "$rounds" -gt 1 ] && echo "-$r" || true)
  for ref in "${refs[@]}"; do
    echo "=== bench_harness: $ref (round $r)"
    "build/harness/$ref/harness/mbi-harness" --out "$out/harness-$ref$suffix.json" "$@"
  done
  echo "=== bench_harness: this checkout (round $r)"
  build/harness/new/harness/mbi-harness --out "$out/harness-new$suffix.json" "$@"
done
