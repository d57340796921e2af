#!/usr/bin/env bash
# Quick start, command 1: install what running needs, build the `mbi` executable alone, and run
# the main job: the twisting bar scene (the paper's Figure 1). Outputs go to out/twist-bar/.
# Extra arguments go to `mbi run`. The tests, benchmarks and their packages are
# scripts/test.sh's (same build folder, build/release).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh run
cmake --preset release >/dev/null
cmake --build --preset release -j "${MBI_JOBS:-$(nproc)}" --target mbi
exec ./build/release/mbi run scenes/twist-bar.toml --out out/twist-bar --force "$@"
