#!/usr/bin/env bash
# Builds the browser page (the web preset: Emscripten, the serial build without CHOLMOD, TetGen,
# OpenMesh or GL) and serves it on http://localhost:8000 (MBI_WEB_PORT). The built folder,
# build/web/page, is plain static files: any web server can serve it.
#   bash scripts/web.sh               build, then serve
#   bash scripts/web.sh --build-only  build only (the browser test's fixture)
set -euo pipefail
cd "$(dirname "$0")/.."
export NODE_PATH=/usr/share/nodejs  # Emscripten's JavaScript optimiser needs Debian's acorn
cmake --preset web >/dev/null
cmake --build --preset web -j "${MBI_JOBS:-$(nproc)}"
if [ "${1:-}" = --build-only ]; then exit 0; fi
port=${MBI_WEB_PORT:-8000}
echo "web: open http://localhost:$port/ (Ctrl-C stops the server)"
exec python3 -m http.server "$port" --bind 127.0.0.1 --directory build/web/page
