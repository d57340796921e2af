#!/usr/bin/env bash
# Quick start, command 2: install dependencies, build, and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${MBI_MODELS_DIR:-}" ] && [ -d ../shared/models ]; then
  export MBI_MODELS_DIR="$(cd ../shared/models && pwd)"
fi
bash scripts/build.sh
ctest --preset release -j "${MBI_JOBS:-$(nproc)}" "$@"
