#!/usr/bin/env bash
# docs/images/viewer.png: `mbi view` on the twisting bar under Xvfb (no GPU or display needed),
# split view BI | modified-BI with the creases in colour, the panel docked at the left;
# docs/images/viewer-looks.png: the same frame in the full looks (ground, shadow, clay, MSAA).
# Usage: scripts/viewer-screenshot.sh [MBI_BINARY]   (default build/release/mbi)
set -euo pipefail
cd "$(dirname "$0")/.."
mbi=${1:-build/release/mbi}
# frame 80 of 120: most of the 90-degree twist is in, the creases of BI are plain to see
xvfb-run -a -s '-screen 0 1400x900x24' "$mbi" view scenes/twist-bar.toml --method modified-bi \
  --creases --frames 80 --width 1280 --height 720 --gpu off --screenshot docs/images/viewer.png --force
xvfb-run -a -s '-screen 0 1400x900x24' "$mbi" view scenes/twist-bar.toml --method modified-bi \
  --looks full --no-panel --frames 80 --width 1280 --height 720 --gpu off --screenshot docs/images/viewer-looks.png --force
echo "wrote docs/images/viewer.png, docs/images/viewer-looks.png"
