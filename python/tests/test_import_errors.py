"""`import mbi` where it cannot work says why and what to do, in one line: an interpreter without
numpy (a virtual environment made without --system-site-packages, as pyenv's python3 here), a
compiled module of another ABI tag (built for another Python), a package without its module."""
import os
import shutil
import subprocess
import sys
import sysconfig

import pytest

import mbi

PACKAGE = os.path.dirname(mbi.__file__)
MODULE = "_mbi" + sysconfig.get_config_var("EXT_SUFFIX")


def import_error(python, parent):
    """The last line of `import mbi` run by python with the package's parent folder on its path."""
    env = dict(os.environ, PYTHONPATH=str(parent))
    result = subprocess.run([str(python), "-c", "import mbi"], capture_output=True, text=True, env=env, cwd=parent)
    assert result.returncode == 1, result.stdout + result.stderr
    return result.stderr.strip().splitlines()[-1]


def copied_package(tmp_path):
    shutil.copytree(PACKAGE, tmp_path / "mbi", ignore=shutil.ignore_patterns("__pycache__"))
    return tmp_path / "mbi"


def test_an_interpreter_without_numpy(tmp_path):
    venv = tmp_path / "bare"  # no --system-site-packages: Debian's numpy is not seen
    made = subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip("python3 -m venv is not available (python3-venv): " + made.stderr)
    python = venv / "bin" / "python"
    line = import_error(python, os.path.dirname(PACKAGE))
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    assert line.startswith(f"ImportError: mbi needs numpy, which this interpreter, {python} ({version}), cannot "
                           f"import"), line
    from mbi import _build
    assert f"mbi was built for {_build.PYTHON} ({_build.VERSION})" in line
    assert f"run that one, or a virtual environment made from it that sees its numpy ({_build.PYTHON} -m venv " \
           f"--system-site-packages VENV" in line
    assert len(line) - 2 * len(str(python)) < 400  # one line of words besides the paths


def test_a_module_built_for_another_python(tmp_path):
    package = copied_package(tmp_path)
    os.rename(package / MODULE, package / "_mbi.cpython-399-x86_64-linux-gnu.so")
    line = import_error(sys.executable, tmp_path)
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    from mbi import _build
    assert line.startswith(f"ImportError: mbi's compiled module _mbi.cpython-399-x86_64-linux-gnu.so was built for "
                           f"{_build.PYTHON} ({_build.VERSION}); this is {sys.executable} ({version}), which loads "
                           f"{MODULE}"), line
    assert f"run {_build.PYTHON}, or build mbi for this interpreter ({sys.executable} -m pip install " \
           f"--no-build-isolation --no-index <mbi source>/python" in line
    assert len(line) - 2 * len(sys.executable) < 450


def test_a_package_without_its_module(tmp_path):
    package = copied_package(tmp_path)
    os.remove(package / MODULE)
    line = import_error(sys.executable, tmp_path)
    assert line.startswith(f"ImportError: mbi's compiled module (_mbi) is missing from {package}"), line
    assert "--target mbi_python" in line and "pip install" in line
