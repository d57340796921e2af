"""The Dask recipe (docs/python.md, "Batches on Dask"): a material sweep, and one cage and one
simulation per model of a folder, run on a LocalCluster of 2 worker processes with one thread
each, give exactly the results (and the files) of the same runs done one by one here."""
import filecmp
import os

import pytest

import mbi

distributed = pytest.importorskip("distributed")

MODELS = os.environ.get("MBI_MODELS_DIR")
# Under ASan every worker is a new instrumented interpreter that imports Dask (tens of seconds
# each) to run code the other tests already cover under ASan: the recipe is tested in release.
pytestmark = pytest.mark.skipif(os.environ.get("MBI_SANITIZED") == "1",
                                reason="Dask's worker processes are slow to start under ASan")


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                       local_directory=str(tmp_path_factory.mktemp("dask")), silence_logs=40)
    with cluster, distributed.Client(cluster) as c:
        yield c


def test_material_sweep_equals_runs_one_by_one(client):
    grid = mbi.batch.material_grid([1e5, 3e5, 1e6], [0.3, 0.45])
    remote = mbi.batch.run_batch(mbi.batch.simulate_material, grid, client, frames=6, points=500)
    local = mbi.batch.run_batch(mbi.batch.simulate_material, grid, frames=6, points=500)
    assert remote == local
    assert len({r["digest"] for r in local}) == len(grid)  # every material gives its own motion
    assert all(r["tip_sag"] > 0 for r in local)


@pytest.mark.skipif(not MODELS, reason="MBI_MODELS_DIR is not set")
def test_folder_of_models_equals_runs_one_by_one(client, tmp_path):
    paths = [os.path.join(MODELS, name) for name in ("woody.obj", "spot.obj")]
    (tmp_path / "dask").mkdir()
    (tmp_path / "local").mkdir()
    remote = mbi.batch.run_batch(mbi.batch.deform_model, paths, client, out_dir=str(tmp_path / "dask"), frames=4)
    local = mbi.batch.run_batch(mbi.batch.deform_model, paths, out_dir=str(tmp_path / "local"), frames=4)
    for r, l in zip(remote, local):
        assert r.pop("obj").startswith(str(tmp_path / "dask")) and l.pop("obj").startswith(str(tmp_path / "local"))
        assert r == l and r["max_displacement"] > 0
    for name in ("woody.obj", "spot.obj"):
        assert filecmp.cmp(tmp_path / "dask" / name, tmp_path / "local" / name, shallow=False)
