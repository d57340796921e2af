#!/usr/bin/env bash
# Quick start, command 2: install every dependency (the run and test sets), build everything and
# run the whole test suite.
#
#   bash scripts/test.sh [CTEST ARGS...]               release preset (build/release)
#   bash scripts/test.sh --sanitizers [CTEST ARGS...]  debug preset, ASan + UBSan (build/debug):
#       the same suite with every sanitizer report fatal; real-model tests skip
#       (MBI_MODELS_DIR is unset for this pass: the release pass runs them, and under ASan they
#       take many minutes), and so do the cases tagged [long]: numerical properties over many
#       steps or frames ("scene large runs" alone takes 9 minutes under ASan) whose code the
#       shorter cases run under the sanitizers too; the release pass runs them all. The browser
#       test (label web) runs in the release pass only: the page is WebAssembly either way, and
#       the native code it is compared with runs under the sanitizers in test_page_model and
#       test_page_scenes (the comparison of the 252K-point scene takes minutes under ASan).
#       LeakSanitizer is on, except in the four test programs that make
#       OpenGL contexts (test_gpu, test_scenes, test_app, test_viewer, and bad-input cases of
#       mbi run / view without --gpu off: Mesa's driver leaks
#       small blocks and is unloaded before exit, so the reports cannot be attributed or
#       suppressed); those run in a second ctest pass with detect_leaks=0. Leaks of the readers
#       are also caught by the fuzz targets (scripts/fuzz.sh). The debug preset builds neither
#       mbi-bench nor the Python module (their run is the release pass's); a module built with the
#       sanitizers by hand runs its tests with the ASan runtime preloaded (python/CMakeLists.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = "--sanitizers" ]; then
  shift
  bash scripts/install-deps.sh test
  cmake --preset debug >/dev/null
  cmake --build --preset debug -j "${MBI_JOBS:-$(nproc)}"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
  # test numbers of the OpenGL programs (gl) and of the others (rest), for ctest -I
  lists=$(ctest --preset debug --show-only=json-v1 | python3 scripts/ctest_lists.py)
  read -r gl rest <<<"$lists"
  status=0
  env -u MBI_MODELS_DIR ASAN_OPTIONS="detect_leaks=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}" \
    ctest --preset debug -j "${MBI_JOBS:-$(nproc)}" -I "$rest" -LE web "$@" || status=1
  env -u MBI_MODELS_DIR ASAN_OPTIONS="detect_leaks=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}" \
    ctest --preset debug -j "${MBI_JOBS:-$(nproc)}" -I "$gl" -LE web "$@" || status=1
  exit $status
fi
if [ -z "${MBI_MODELS_DIR:-}" ] && [ -d ../shared/models ]; then
  export MBI_MODELS_DIR="$(cd ../shared/models && pwd)"
fi
bash scripts/build.sh
ctest --preset release -j "${MBI_JOBS:-$(nproc)}" "$@"
