#!/usr/bin/env bash
# Runs the benchmarks (mbi-bench) and writes the report:
#   bench/results/<date>-<host>.json   Google Benchmark JSON, with this machine and commit
#   bench/results/<date>-<host>.md     the report (scripts/bench_report.py), with PNG plots beside it
#
#   bash scripts/bench.sh            full run: every benchmark 3 times in random order, the medians
#                                    reported (about 6 minutes on a 2-core machine, plus the build)
#   bash scripts/bench.sh --quick    small sizes, short runs, no 10K precompute (under a minute),
#                                    and the Python frame loop (python/bench/frame_loop.py --quick,
#                                    a few seconds) when the release build has the Python module;
#                                    writes to build/bench-quick/ unless --out is given (CI)
#   bash scripts/bench.sh --out DIR  write into DIR instead
#   MBI_BENCH_BASELINE=OLD.json      an earlier run (e.g. before a change): its target figures as
#                                    a 'before' column (the report says if it ran elsewhere)
#   MBI_BENCH_REPETITIONS=N          repetitions of each benchmark (default 3; --quick: 1)
#
# Installs missing Debian packages (scripts/install-deps.sh test) and builds mbi-bench with the
# release preset first (set MBI_BENCH_NO_BUILD=1 to skip both). Uses the scanned models beside
# the clone (../shared/models) or $MBI_MODELS_DIR for the bunny row of Table 1. Fails when
# mbi-bench or the report fails.
# Run nothing else meanwhile: the numbers are only as quiet as the machine.
set -euo pipefail
cd "$(dirname "$0")/.."

quick=0
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --out) out="$2"; shift ;;
    -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
    *) echo "bench.sh: error: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [ -z "$out" ]; then
  if [ "$quick" = 1 ]; then out=build/bench-quick; else out=bench/results; fi
fi

if [ "${MBI_BENCH_NO_BUILD:-0}" != 1 ]; then
  bash scripts/install-deps.sh test
  cmake --preset release >/dev/null
  cmake --build --preset release -j "${MBI_JOBS:-$(nproc)}" --target mbi-bench
fi
if [ -z "${MBI_MODELS_DIR:-}" ] && [ -d ../shared/models ]; then
  export MBI_MODELS_DIR="$(cd ../shared/models && pwd)"
fi
# Debian's python3-matplotlib belongs to Debian's interpreter (another python3 may come first).
python=/usr/bin/python3
[ -x "$python" ] || python=python3

mkdir -p "$out"
stamp="$(date +%Y-%m-%d)-$(hostname -s 2>/dev/null || hostname)"
json="$out/$stamp.json"
start=$(date +%s)
reps="${MBI_BENCH_REPETITIONS:-$([ "$quick" = 1 ] && echo 1 || echo 3)}"
repeat=()
if [ "$reps" -gt 1 ]; then
  # interleaved at random, so that a slow spell of a shared machine spreads over many benchmarks
  repeat=(--benchmark_repetitions="$reps" --benchmark_enable_random_interleaving=true
          --benchmark_report_aggregates_only=true)
fi
MBI_BENCH_QUICK=$quick build/release/mbi-bench "${repeat[@]}" \
  --benchmark_out="$json" --benchmark_out_format=json --benchmark_counters_tabular=false
wall=$(( $(date +%s) - start ))
echo "bench.sh: mbi-bench took ${wall} s"
baseline=()
[ -n "${MBI_BENCH_BASELINE:-}" ] && baseline=(--baseline "$MBI_BENCH_BASELINE")
"$python" scripts/bench_report.py "$json" --machine --wall-s "$wall" "${baseline[@]}"
if [ "$quick" = 1 ] && [ -f build/release/python/mbi/__init__.py ]; then
  # the module's interpreter (CMake's Python_EXECUTABLE), not necessarily the report's
  module_python=$(sed -n 's/^PYTHON = "\(.*\)"$/\1/p' build/release/python/mbi/_build.py)
  PYTHONPATH=build/release/python "${module_python:-$python}" python/bench/frame_loop.py --quick |
    tee "$out/$stamp-python.md"
fi
