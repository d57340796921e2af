"""The examples under python/examples run and reach what they state; the benchmark runs."""
import os
import subprocess
import sys

import pytest

import mbi

EXAMPLES = os.path.join(os.path.dirname(__file__), os.pardir, "examples")
SMALL = os.environ.get("MBI_SANITIZED") == "1"  # ASan is far slower: smaller sizes there


def run(name, *args):
    result = subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args], capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_simulator_loop():
    out = run("simulator_loop.py", "--points", "2000" if SMALL else "20000", "--frames", "10")
    assert "ok: the dense model follows the simulated bar" in out


@pytest.mark.parametrize("method", ["bi", "modified-bi", "phong"])
def test_torch_fit(method):
    pytest.importorskip("torch")
    out = run("torch_fit.py", "--method", method, "--points", "500" if SMALL else "2000")
    assert "ok: the control mesh was fitted" in out


def test_overhead_benchmark_runs():
    """python/bench/overhead.py, tiny (the real run is in docs/python.md), so that it cannot rot:
    with a module built with its clocks (MBI_PYTHON_TIMING=ON) it runs; the shipped module has
    none, reads no clock in its calls, and the benchmark says how to build one that has."""
    bench = os.path.join(os.path.dirname(__file__), os.pardir, "bench", "overhead.py")
    result = subprocess.run([sys.executable, bench, "--calls", "20", "--points", "2000" if SMALL else "20000",
                             "--vjp-calls", "2"],
                            capture_output=True, text=True, timeout=600)
    if mbi._mbi._timing is None:
        assert result.returncode == 2, result.stdout + result.stderr
        assert "-DMBI_PYTHON_TIMING=ON" in result.stderr
        return
    assert result.returncode == 0, result.stdout + result.stderr
    assert "vjp / deform" in result.stdout


@pytest.mark.skipif(not os.environ.get("MBI_MODELS_DIR"), reason="MBI_MODELS_DIR is not set")
def test_deform_model_keeps_the_texture(tmp_path):
    """A real model (spot, with texture coordinates) deformed with a generated cage: the OBJ
    written keeps every `vt` of the input (the example compares them and says so)."""
    out = tmp_path / "spot.obj"
    text = run("deform_model.py", "--out", str(out), "--frames", "5" if SMALL else "15", "--vertices", "120")
    assert "ok: the deformed model keeps its" in text
    model = os.path.join(os.environ["MBI_MODELS_DIR"], "spot.obj")
    vt = [line for line in open(model) if line.startswith("vt ")]
    assert len(vt) > 0 and [line for line in open(out) if line.startswith("vt ")] == vt


@pytest.mark.skipif(SMALL, reason="Dask's worker processes are slow to start under ASan (test_dask.py says why)")
def test_dask_sweep_on_two_workers():
    pytest.importorskip("distributed")
    text = run("dask_sweep.py", "--workers", "2", "--frames", "5", "--points", "1000", "--check")
    assert "8 runs on 2 worker(s)" in text and "ok: the batch equals the same runs one by one" in text
