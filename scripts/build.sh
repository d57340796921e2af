#!/usr/bin/env bash
# Configures and builds mbi with the release preset (installs dependencies first).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "${MBI_JOBS:-$(nproc)}"
