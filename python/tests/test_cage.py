"""mbi.cage against `mbi cage`: the same model gives the same control mesh (both call the same
deterministic generator; the command writes it with %.17g), for both meshers; flat models and
bad arguments are refused naming what is wrong."""
import os
import subprocess

import numpy as np
import pytest

import mbi

MBI = os.environ.get("MBI_EXE")
MODELS = os.environ.get("MBI_MODELS_DIR")


def sphere(n=12):
    """A closed UV sphere of radius 1 (V (k, 3), F (t, 3)), a model for the cage."""
    th, ph = np.meshgrid(np.linspace(0, np.pi, n)[1:-1], np.linspace(0, 2 * np.pi, 2 * n, endpoint=False), indexing="ij")
    V = np.concatenate([[[0, 0, 1]], np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3),
                        [[0, 0, -1]]])
    rings, m = th.shape
    F = []
    for j in range(m):
        F.append([0, 1 + j, 1 + (j + 1) % m])
        F.append([len(V) - 1, 1 + (rings - 1) * m + (j + 1) % m, 1 + (rings - 1) * m + j])
        for i in range(rings - 1):
            a, b = 1 + i * m + j, 1 + i * m + (j + 1) % m
            F += [[a, a + m, b], [b, a + m, b + m]]
    return V, np.array(F)


@pytest.mark.skipif(not MBI or not os.path.exists(MBI), reason="the mbi command line is not built")
@pytest.mark.parametrize("mesher", ["voxel", "tetgen"])
def test_cage_equals_mbi_cage(tmp_path, mesher):
    V, F = sphere()
    mbi.write_surface(tmp_path / "sphere.obj", V, F)
    subprocess.run([MBI, "cage", str(tmp_path / "sphere.obj"), "--vertices", "60", "--mesher", mesher,
                    "--out", str(tmp_path / "cage")], check=True, capture_output=True)
    U, T = mbi.read_control_mesh(tmp_path / "cage")
    cage = mbi.cage(mbi.read_surface(tmp_path / "sphere.obj").V, F, vertices=60, mesher=mesher)
    np.testing.assert_array_equal(cage.U, U)
    np.testing.assert_array_equal(cage.T, T)
    assert cage.mesher == mesher and cage.dim == 3 and cage.outside_points == 0
    assert cage.min_dihedral_deg > 0 and cage.cell_size > 0
    mbi.validate_mesh(*cage)


@pytest.mark.skipif(not MODELS, reason="MBI_MODELS_DIR is not set")
def test_cage_of_a_real_model_holds_it():
    mesh = mbi.read_surface(os.path.join(MODELS, "spot.obj"))
    U, T = mbi.cage(mesh.V, mesh.F, vertices=120)
    assert 80 <= len(U) <= 160
    assert len(mbi.embed(U, T, mesh.V).outside) == 0


def test_flat_models_and_bad_arguments():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    F = np.array([[0, 1, 2], [0, 2, 3]])
    flat = mbi.cage(V, F, vertices=20)
    assert flat.dim == 2 and flat.T.shape[1] == 3
    assert mbi.cage(V, F, vertices=20, force_3d=True).dim == 3
    with pytest.raises(ValueError, match="V is flat"):
        mbi.cage(V, F, vertices=20, mesher="tetgen")
    with pytest.raises(ValueError, match="mesher"):
        mbi.cage(V, F, mesher="octree")
    with pytest.raises(ValueError, match=r"V must have shape \(n, 3\)"):
        mbi.cage(V[:, :2], F)
    with pytest.raises(ValueError, match=r"^vertices 2 out of range"):
        mbi.cage(V, F, vertices=2)
