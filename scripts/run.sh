#!/usr/bin/env bash
# Quick start, command 1: install dependencies, build, and run the main job: the twisting bar
# scene (the paper's Figure 1). Outputs go to out/twist-bar/. Extra arguments go to `mbi run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
exec ./build/release/mbi run scenes/twist-bar.toml --out out/twist-bar --force "$@"
