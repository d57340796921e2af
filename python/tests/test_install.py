"""The documented install into a virtual environment, offline: a venv that sees Debian's numpy
(--system-site-packages), `cmake --install <build> --component python --prefix <venv>`, then
`import mbi` from the venv's interpreter outside the build tree."""
import os
import shutil
import subprocess
import sys

import pytest

BUILD = os.environ.get("MBI_BUILD_DIR")


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
