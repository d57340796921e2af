#!/usr/bin/env bash
# Installs every build and test dependency of mbi from Debian 12 packages.
# Idempotent: packages already present are skipped; nothing is downloaded outside apt.
# Run as root (or with sudo).
set -euo pipefail

# Only what the build uses: Eigen (interp, sim, pipeline), TetGen and OpenMesh (control meshes,
# subdivision), stb (PNG), toml11 (scenes), CLI11 (command line), nlohmann-json (reports),
# Catch2 (tests), Google Benchmark (mbi-bench); OpenGL for the GPU evaluator and renderer: libepoxy
# (the one GL loader), EGL/GL headers, and Mesa's EGL and llvmpipe driver so that the GPU path runs
# headless on machines without a GPU (CI); GLFW, Dear ImGui and Xvfb (with xauth, which
# xvfb-run needs) for the viewer and its tests; matplotlib for the plots of the benchmark report
# (scripts/bench.sh); SuiteSparse for CHOLMOD, the optional faster factorization of the
# modified-BI precompute (interp builds without it: MBI_WITH_CHOLMOD=OFF), and OpenBLAS, which
# CHOLMOD's supernodal factorization runs on (Debian's reference BLAS is several times slower;
# the package takes over libblas.so.3 through update-alternatives); clang with its libFuzzer runtime for the fuzz targets of the readers
# (scripts/fuzz.sh, docs/hardening.md).
packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libtet1.5-dev libopenmesh-dev
  libtoml11-dev libcli11-dev nlohmann-json3-dev libstb-dev
  catch2 libbenchmark-dev
  libepoxy-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  libglfw3-dev libimgui-dev libglx-mesa0 xvfb xauth
  python3-matplotlib
  libsuitesparse-dev libopenblas0-pthread
  clang libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
    echo "install-deps: missing packages (${missing[*]}) and not root; run as root" >&2
    exit 1
  fi
else
  SUDO=
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
