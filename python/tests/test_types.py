"""The types: `mypy --strict` (Debian's python3-mypy) passes on the examples and on
python/tests/typing/usage.py, which calls every public name of mbi with the result types a user
expects written out (Literal constants into Literal arguments, the overloads of deform, vjp and
evaluate, box_mesh, run_scene, mbi.batch, mbi.torch); and usage.py runs, so its calls are real."""
import importlib.util
import os
import subprocess
import sys

import pytest

import mbi

HERE = os.path.dirname(os.path.abspath(__file__))
PYTHON_DIR = os.path.dirname(HERE)
PACKAGE_PARENT = os.path.dirname(os.path.dirname(mbi.__file__))
USAGE = os.path.join(HERE, "typing", "usage.py")


def mypy(*paths, cache):
    env = dict(os.environ, MYPYPATH=PACKAGE_PARENT)
    return subprocess.run([sys.executable, "-m", "mypy", "--config-file", os.path.join(PYTHON_DIR, "mypy.ini"),
                           "--cache-dir", str(cache), *paths], capture_output=True, text=True, env=env, timeout=900)


@pytest.mark.skipif(importlib.util.find_spec("mypy") is None, reason="needs mypy (python3-mypy)")
def test_mypy_strict_on_the_examples_and_every_public_name(tmp_path):
    examples = os.path.join(PYTHON_DIR, "examples")
    result = mypy(examples, USAGE, cache=os.environ.get("MBI_BUILD_DIR", str(tmp_path)) + "/mypy-cache")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Success: no issues found in 5 source files" in result.stdout


@pytest.mark.skipif(importlib.util.find_spec("mypy") is None, reason="needs mypy (python3-mypy)")
def test_mypy_catches_a_wrong_literal_and_a_wrong_result_type(tmp_path):
    """The check can fail: a method name that is not a Literal of METHODS, and deform's float32
    result taken as float64, are errors."""
    bad = tmp_path / "bad.py"
    bad.write_text("import numpy as np\nimport numpy.typing as npt\nimport mbi\n"
                   "U, T = mbi.box_mesh(1, 1, 1)\n"
                   "d = mbi.Deformer(U, T, U, method='modified_bi')\n"
                   "x: npt.NDArray[np.float64] = d.deform(U, dtype=np.float32)\n")
    result = mypy(str(bad), cache=tmp_path / "cache")
    assert result.returncode == 1
    assert "bad.py:5: error" in result.stdout and "bad.py:6: error" in result.stdout, result.stdout


def test_the_typing_usage_names_every_public_name():
    text = open(USAGE).read()
    assert [name for name in mbi.__all__ if f"mbi.{name}" not in text] == []
    assert [name for name in mbi.batch.__all__ if f"mbi.batch.{name}" not in text] == []
    assert all(f"mbi.torch.{name}" in text for name in ("deform", "Deform", "DeformFunction", "VjpFunction"))


def test_the_typing_usage_runs(tmp_path):
    pytest.importorskip("torch")
    result = subprocess.run([sys.executable, USAGE, str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "ok: every public name was called" in result.stdout
