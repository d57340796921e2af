"""Many simulations at once on Dask: a sweep over material parameters (a clamped bar sagging
under gravity, one run per Young's modulus and Poisson ratio) and, with --models, one cage and
one simulation per model of a folder, run on a dask.distributed cluster, one task a run.

Only small things cross the wire: the task functions of mbi.batch take parameters and paths and
return dicts of numbers; the meshes, cages, simulators and pipelines are built on the worker.
Each worker process runs one task at a time on one mbi thread, so the cores are shared by tasks
rather than by the threads of one task. --check reruns the batch one by one in this process and
compares (the results are bitwise equal).

    PYTHONPATH=build/release/python python3 python/examples/dask_sweep.py --workers 2 [--check]
    ... --scheduler tcp://host:8786      # an existing cluster instead of a local one
"""
import argparse
import os
import tempfile
import time
from typing import Any, Dict, List, Optional, Tuple

import mbi
from mbi.batch import deform_model, material_grid, run_batch, simulate_material


def run(client: Optional[Any], a: argparse.Namespace, out_dir: str) -> Tuple[List[Dict[str, Any]], float]:
    """The sweep and the models on `client` (None: one by one here); results and wall time (s)."""
    t0 = time.perf_counter()
    grid = material_grid([2e5, 5e5, 1e6, 2e6], [0.3, 0.45])
    results = run_batch(simulate_material, grid, client, frames=a.frames, points=a.points)
    if a.models:
        paths = sorted(os.path.join(a.models, f) for f in os.listdir(a.models) if f.endswith(".obj"))
        results += run_batch(deform_model, paths, client, out_dir=out_dir, frames=a.frames)
    return results, time.perf_counter() - t0


def without_paths(results: List[Dict[str, Any]]) -> List[Dict[str, Any]]:
    return [{k: v for k, v in r.items() if k != "obj"} for r in results]


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=2, help="local worker processes (0: no Dask, one by one)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (instead of --workers)")
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--points", type=int, default=200000, help="dense points of each sweep run")
    parser.add_argument("--models", help="a folder of .obj models: one cage and one simulation each")
    parser.add_argument("--out", default=None, help="folder of the deformed models (default: a temporary one)")
    parser.add_argument("--check", action="store_true", help="compare with the same runs one by one")
    a = parser.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="mbi_sweep_")

    if a.scheduler or a.workers > 0:
        from dask.distributed import Client, LocalCluster
        cluster = None if a.scheduler else LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                                                        dashboard_address=":0", silence_logs=40)
        with Client(a.scheduler or cluster) as client:
            results, seconds = run(client, a, out)
        if cluster is not None:
            cluster.close()
    else:
        results, seconds = run(None, a, out)
    for r in results:
        print({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items() if k != "digest"})
    where = a.scheduler or (f"{a.workers} worker(s)" if a.workers else "one by one")
    print(f"{len(results)} runs on {where}: {seconds:.2f} s")
    if a.check:
        local, _ = run(None, a, tempfile.mkdtemp(prefix="mbi_sweep_check_"))
        if without_paths(local) != without_paths(results):
            raise SystemExit("the batch differs from the runs one by one")
        print("ok: the batch equals the same runs one by one")


if __name__ == "__main__":
    main()
