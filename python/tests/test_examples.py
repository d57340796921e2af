"""The examples under python/examples run and reach what they state; the benchmark runs."""
import os
import subprocess
import sys

import pytest

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
    """python/bench/overhead.py, tiny (the real run is in docs/python.md), so that it cannot rot."""
    bench = os.path.join(os.path.dirname(__file__), os.pardir, "bench", "overhead.py")
    result = subprocess.run([sys.executable, bench, "--calls", "20", "--points", "2000" if SMALL else "20000",
                             "--vjp-calls", "2"],
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "vjp / deform" in result.stdout
