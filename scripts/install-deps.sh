#!/usr/bin/env bash
# Installs mbi's dependencies from Debian 12 packages, in two sets:
#   bash scripts/install-deps.sh run    what building and running `mbi` needs (scripts/run.sh)
#   bash scripts/install-deps.sh test   the run set and what the tests, the benchmarks and the
#                                       fuzz targets need (scripts/test.sh, bench.sh, fuzz.sh)
# Without an argument: test. Idempotent: packages already present are skipped; nothing is
# downloaded outside apt. Run as root (or with sudo).
set -euo pipefail

# Building and running mbi: the compiler, CMake and Ninja; Eigen (interp, sim, pipeline); TetGen
# and OpenMesh (control meshes, subdivision); toml11 (scenes), CLI11 (command line),
# nlohmann-json (reports), stb (PNG); OpenGL for the GPU evaluator, the renderer and the viewer:
# libepoxy (the one GL loader), EGL/GL headers, Mesa's EGL, GLX and llvmpipe driver (so that the
# GPU path runs on machines without a GPU), GLFW and Dear ImGui; SuiteSparse for CHOLMOD, the
# faster factorization of the modified-BI precompute (optional: MBI_WITH_CHOLMOD), and OpenBLAS,
# which CHOLMOD's supernodal factorization runs on (Debian's reference BLAS is several times
# slower; the package takes over libblas.so.3 through update-alternatives); pugixml and zlib
# for VTK XML (.vtu, .pvd) control meshes and trajectories; tinygltf (header-only) for glTF 2.0;
# OpenVDB (it brings TBB, Imath and blosc) for mesh colliders' level sets (MBI_WITH_OPENVDB).
run_packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libtet1.5-dev libopenmesh-dev
  libtoml11-dev libcli11-dev nlohmann-json3-dev libstb-dev
  libepoxy-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libglx-mesa0
  libglfw3-dev libimgui-dev
  libsuitesparse-dev libopenblas0-pthread
  libpugixml-dev zlib1g-dev libtinygltf-dev
  libopenvdb-dev
)
# Testing: Catch2 (the test suite), Xvfb with xauth (the viewer's tests run under xvfb-run),
# Python (scripts/test.sh --sanitizers), Google Benchmark (mbi-bench), matplotlib and git (the
# benchmark report's plots and commit), clang with its libFuzzer runtime (scripts/fuzz.sh);
# the Python package (python/: pybind11, the headers, numpy, pytest, PyTorch for its autograd
# wrapper, venv for the install test, Dask's distributed scheduler for the batch recipe and its
# test on a LocalCluster); meshio (the VTK XML fixtures' writer, tests/data/vtu); ffmpeg (the
# viewer's --video pipes frames to it at run time, optional; its tests use ffprobe); Emscripten
# (the web preset; its linker needs Debian's acorn) and Chromium (the page's browser test);
# Blender (headless, `blender -b`: its glTF importer reads our files back).
test_packages=(
  catch2 xvfb xauth python3
  libbenchmark-dev python3-matplotlib git
  clang libclang-rt-14-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-torch python3-venv python3-setuptools
  python3-meshio python3-distributed python3-hypothesis python3-mypy ffmpeg
  emscripten node-acorn chromium blender
)
# The glTF tests check our files with the Khronos validator and three.js, the browser test drives
# chromium with playwright-core (node packages pinned by tests/gltf/node/package-lock.json and
# web/test/package-lock.json, installed by `npm ci` below): node and npm from Debian where
# no npm is installed already (a NodeSource node brings its own).
if ! command -v npm >/dev/null 2>&1; then test_packages+=(nodejs npm); fi

# The node packages of the glTF tests and of the browser test (playwright-core, web/test), into
# their node_modules (git-ignored).
install_node_packages() {
  local root dir
  root="$(cd "$(dirname "$0")/.." && pwd)"
  for dir in "$root/tests/gltf/node" "$root/web/test"; do
    if [ -d "$dir/node_modules" ]; then continue; fi
    echo "install-deps: npm ci in ${dir#"$root"/}"
    (cd "$dir" && npm ci --no-audit --no-fund)
  done
}

case "${1:-test}" in
  run) packages=("${run_packages[@]}") ;;
  test) packages=("${run_packages[@]}" "${test_packages[@]}") ;;
  -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
  *) echo "install-deps: error: unknown set '$1' (run or test)" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  if [ "${1:-test}" = test ]; then install_node_packages; fi
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
if [ "${1:-test}" = test ]; then install_node_packages; fi
