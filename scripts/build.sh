#!/usr/bin/env bash
# Installs every dependency (the run and test sets) and builds everything with the release
# preset: mbi, the tests, mbi-bench.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh test
cmake --preset release >/dev/null
cmake --build --preset release -j "${MBI_JOBS:-$(nproc)}"
