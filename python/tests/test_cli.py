"""The package agrees with the command line: `mbi deform` on the same control mesh, pose and
points gives the same positions (it writes them with %.17g) and the same discontinuity table."""
import json
import os
import subprocess

import numpy as np
import pytest

import mbi
import meshes

MBI = os.environ.get("MBI_EXE")
pytestmark = pytest.mark.skipif(not MBI or not os.path.exists(MBI), reason="the mbi command line is not built")


def write_tetgen(base, U, T):
    with open(f"{base}.node", "w") as f:
        f.write(f"{len(U)} {U.shape[1]} 0 0\n")
        for i, u in enumerate(U):
            f.write(f"{i} " + " ".join(f"{v:.17g}" for v in u) + "\n")
    with open(f"{base}.ele", "w") as f:
        f.write(f"{len(T)} {T.shape[1]} 0\n")
        for e, t in enumerate(T):
            f.write(f"{e} " + " ".join(str(v) for v in t) + "\n")


@pytest.mark.parametrize("method", ["bi", "modified-bi", "phong"])
def test_deform_agrees_with_mbi_deform(tmp_path, mesh, method):
    U, T = mesh
    P = meshes.points(U, 300)
    X = meshes.pose(U)
    write_tetgen(tmp_path / "rest", U, T)
    np.savetxt(tmp_path / "pose.txt", X, fmt="%.17g")
    np.savetxt(tmp_path / "points.txt", P, fmt="%.17g")
    run = subprocess.run([MBI, "deform", "--control", str(tmp_path / "rest.node"), "--deformed",
                          str(tmp_path / "pose.txt"), "--mesh", str(tmp_path / "points.txt"), "--out",
                          str(tmp_path / "out.txt"), "--method", method, "--alpha", "0.15", "--stats",
                          str(tmp_path / "stats.json")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    cli = np.loadtxt(tmp_path / "out.txt", ndmin=2)
    ours = mbi.Deformer(U, T, P, method=method, alpha=0.15).deform(X)
    assert np.abs(cli - ours).max() <= 1e-13 * (1 + np.abs(ours).max())

    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["control_vertices"] == len(U) and stats["points"] == 300
    solver = mbi.ModifiedBI(U, T, alpha=0.15)
    assert stats["beta"] == pytest.approx(solver.beta, rel=1e-12)
    table = mbi.discontinuity_table(solver, X, solver.solve(X), mbi.Phong(U, T).M(X))
    disc = stats["disc"]
    for name, ours_summary in (("bi", table.bi), ("modified_bi", table.modified_bi), ("phong", table.phong)):
        for field in ("mean", "std", "max"):
            assert disc[name][field] == pytest.approx(getattr(ours_summary, field), rel=1e-9), (name, field)
