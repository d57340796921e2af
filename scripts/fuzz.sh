#!/usr/bin/env bash
# Runs the libFuzzer targets of the readers (tests/fuzz/, docs/hardening.md).
#
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
#
# SECONDS per target (default 20); TARGETs from: obj off ply stl gltf gltf_files points tetgen gmsh vtk vtu pvd
# pc2 mdd png scene script (default: all). Configures and builds a separate clang build in build/fuzz
# (-DMBI_FUZZ=ON: the readers only, with -fsanitize=fuzzer,address,undefined), then runs the
# targets, as many at once as there are cores (MBI_JOBS). Each starts from its seeds
# (tests/fuzz/<target>/, read only) and the inputs found by earlier runs
# (build/fuzz/corpus/<target>/, kept between runs). A crash, leak, sanitizer report, timeout
# (10 s for one input) or out-of-memory (2 GB) stops that target; its input is saved as build/fuzz/artifacts/<target>/crash-* (or leak-, timeout-,
# oom-) and the script exits 1 after the other targets have run. MBI_FUZZ_SEED fixes
# libFuzzer's random seed (CI: 1 unless set, so that a CI run explores the same way each time and
# does not fail on a find of another day; runs by hand draw a new seed each time).
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-20}
shift || true
all=(obj off ply stl gltf gltf_files points tetgen gmsh vtk vtu pvd pc2 mdd png scene script)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz.sh: unknown target '$t' (known: ${all[*]})" >&2; exit 2; }
done

bash scripts/install-deps.sh test   # clang and its libFuzzer runtime are in the test set
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
if [ ! -f build/fuzz/CMakeCache.txt ]; then
  CC=clang CXX=clang++ cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DMBI_FUZZ=ON -DMBI_BUILD_TESTS=OFF -DMBI_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
fi
cmake --build build/fuzz -j "${MBI_JOBS:-$(nproc)}" --target "${targets[@]/#/fuzz_}"

seed=()
if [ -n "${MBI_FUZZ_SEED:-}" ]; then seed=(-seed="$MBI_FUZZ_SEED")
elif [ -n "${CI:-}" ]; then seed=(-seed=1)
fi
# fuzz_one TARGET: runs it, prints its summary in one piece (targets run side by side), and
# leaves build/fuzz/failed-TARGET behind when it found something
fuzz_one() {
  local t=$1 corpus=build/fuzz/corpus/$1 artifacts=build/fuzz/artifacts/$1 log=build/fuzz/fuzz_$1.log
  mkdir -p "$corpus" "$artifacts"
  if ! build/fuzz/tests/fuzz/fuzz_$t -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
       -print_final_stats=1 "${seed[@]}" \
       -artifact_prefix="$artifacts/" "$corpus" "tests/fuzz/$t" >"$log" 2>&1; then
    touch "build/fuzz/failed-$t"
    { echo "== fuzz_$t: ${secs} s"; tail -n 40 "$log"; }
    echo "fuzz_$t FAILED: input(s) in $artifacts/, log $log" >&2
  else
    echo "== fuzz_$t: ${secs} s: $(grep -E "^stat::number_of_executed_units|^stat::new_units_added" "$log" | tr '\n' ' ')"
  fi
}
# one target a core at a time (each is one process on one thread)
rm -f build/fuzz/failed-*
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "${MBI_JOBS:-$(nproc)}" ]; do wait -n || true; done
  fuzz_one "$t" &
done
wait
failed=()
for t in "${targets[@]}"; do
  [ -e "build/fuzz/failed-$t" ] && failed+=("$t")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: failures in: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz.sh: ${#targets[@]} target(s), ${secs} s each, no failure"
