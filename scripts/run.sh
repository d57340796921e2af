#!/usr/bin/env bash
# Quick start, command 1: install dependencies, build, and run the main job.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
if [ -f scenes/twist-bar.toml ] && ./build/release/mbi run --help >/dev/null 2>&1; then
  exec ./build/release/mbi run scenes/twist-bar.toml --out out/twist-bar --force "$@"
else
  exec ./build/release/mbi deform --example twist-bar "$@"
fi
