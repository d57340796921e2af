"""The documented installs into a virtual environment, offline, in a venv that sees Debian's numpy
(--system-site-packages): `pip install --no-build-isolation --no-index python` (here taking the
module of the build tree, MBI_PYTHON_BUILD_DIR, as CI does: one build), with its metadata, and
`pip uninstall` leaving nothing; and `cmake --install <build> --component python --prefix <venv>`.
Each imports mbi from the venv's interpreter outside the build tree."""
import importlib.util
import os
import re
import shutil
import subprocess
import sys

import pytest

import mbi

BUILD = os.environ.get("MBI_BUILD_DIR")
SOURCE = os.environ.get("MBI_SOURCE_DIR", os.path.join(os.path.dirname(__file__), os.pardir, os.pardir))
PYTHON_DIR = os.path.join(SOURCE, "python")


def project_version():
    with open(os.path.join(SOURCE, "CMakeLists.txt")) as f:
        return re.search(r"project\(mbi\s+VERSION\s+([0-9.]+)", f.read()).group(1)


def venv_with_pip(tmp_path):
    venv = tmp_path / "venv"
    if importlib.util.find_spec("ensurepip") is None:
        pytest.skip("python3 -m venv is not available (python3-venv)")
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)],
                          capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip("python3 -m venv is not available (python3-venv): " + made.stderr)
    return venv


def clean_env(**extra):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "MBI_PYTHON_BUILD_DIR")}
    env.update(extra)
    return env


def files_under(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.mark.skipif(not BUILD, reason="needs the build folder (MBI_BUILD_DIR)")
def test_pip_install_metadata_and_uninstall(tmp_path):
    venv = venv_with_pip(tmp_path)
    pip, python = str(venv / "bin" / "pip"), str(venv / "bin" / "python")
    before = files_under(venv)
    env = clean_env(MBI_PYTHON_BUILD_DIR=BUILD, PIP_NO_CACHE_DIR="1")
    install = subprocess.run([pip, "install", "--no-build-isolation", "--no-index", PYTHON_DIR],
                             capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600)
    assert install.returncode == 0, install.stdout + install.stderr
    version = project_version()
    assert mbi.__version__ == version
    show = subprocess.run([pip, "show", "mbi"], capture_output=True, text=True, env=clean_env())
    assert show.returncode == 0 and f"Version: {version}" in show.stdout.splitlines(), show.stdout
    check = subprocess.run([python, "-c", "import importlib.metadata, mbi, numpy as np; "
                            "print(importlib.metadata.version('mbi')); print(mbi.__file__); "
                            "U, T = mbi.box_mesh(1, 1, 1); print(mbi.Deformer(U, T, U).deform(U + 1)[0].tolist())"],
                           capture_output=True, text=True, env=clean_env(), cwd=tmp_path)
    assert check.returncode == 0, check.stderr
    lines = check.stdout.splitlines()
    assert lines[0] == version and lines[1].startswith(str(venv)) and lines[2] == "[1.0, 1.0, 1.0]"
    example = subprocess.run([python, os.path.join(PYTHON_DIR, "examples", "simulator_loop.py"), "--points", "500",
                              "--frames", "3"], capture_output=True, text=True, env=clean_env(), cwd=tmp_path)
    assert example.returncode == 0 and "ok:" in example.stdout, example.stdout + example.stderr
    uninstall = subprocess.run([pip, "uninstall", "-y", "mbi"], capture_output=True, text=True, env=clean_env())
    assert uninstall.returncode == 0, uninstall.stderr
    assert files_under(venv) == before  # every file it installed (the compiled module, caches) is gone


@pytest.mark.skipif(not BUILD, reason="needs the build folder (MBI_BUILD_DIR)")
def test_pip_install_refuses_a_build_tree_without_the_module(tmp_path):
    venv = venv_with_pip(tmp_path)
    (tmp_path / "empty").mkdir()
    env = clean_env(MBI_PYTHON_BUILD_DIR=str(tmp_path / "empty"), PIP_NO_CACHE_DIR="1")
    install = subprocess.run([str(venv / "bin" / "pip"), "install", "--no-build-isolation", "--no-index", PYTHON_DIR],
                             capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600)
    assert install.returncode != 0
    assert f"MBI_PYTHON_BUILD_DIR={tmp_path / 'empty'}: no _mbi." in install.stdout + install.stderr


@pytest.mark.skipif(not BUILD or not shutil.which("cmake"), reason="needs the build folder and cmake")
def test_cmake_install_into_a_venv(tmp_path):
    venv = tmp_path / "venv"
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)],
                          capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip("python3 -m venv is not available (python3-venv): " + made.stderr)
    install = subprocess.run(["cmake", "--install", BUILD, "--component", "python", "--prefix", str(venv)],
                             capture_output=True, text=True)
    assert install.returncode == 0, install.stdout + install.stderr
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    check = subprocess.run([str(venv / "bin" / "python"), "-c",
                            "import mbi, numpy as np; "
                            "U = np.array([[0., 0.], [1, 0], [0, 1], [1, 1]]); T = np.array([[0, 1, 2], [1, 3, 2]]); "
                            "d = mbi.Deformer(U, T, [[0.25, 0.25], [0.7, 0.6]]); "
                            "print(mbi.__file__); print(abs(d.deform(U + 1) - [[1.25, 1.25], [1.7, 1.6]]).max() < 1e-15)"],
                           capture_output=True, text=True, cwd=tmp_path, env=env)
    assert check.returncode == 0, check.stderr
    assert check.stdout.splitlines()[0].startswith(str(venv))
    assert check.stdout.splitlines()[1] == "True"
