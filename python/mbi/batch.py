"""Batches of independent runs, one by one or on a Dask cluster (docs/python.md, "Batches on Dask").

A simulation is sequential over its frames, so a batch is split by run: one task a parameter set
or a model. Each task below takes and returns small picklable values (paths, numbers, dicts of
numbers and strings) and builds its heavy objects (surfaces, cages, simulators, pipelines: C++
objects that do not pickle) in the process that runs it; the outputs it writes go to files.
Every task runs mbi on `threads` threads (1 by default: a Dask worker with one thread a core).
"""
import hashlib
import os
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

from . import _mbi
from .meshes import box_mesh

__all__ = ["deform_model", "digest", "material_grid", "run_batch", "simulate_material"]


def digest(A: npt.ArrayLike) -> str:
    """A short fingerprint of an array's exact values (equal digests: bitwise equal results)."""
    return hashlib.sha256(np.ascontiguousarray(A, dtype=np.float64).tobytes()).hexdigest()[:16]


def material_grid(youngs_moduli: Iterable[float], poisson_ratios: Sequence[float],
                  density: float = 500.0) -> List[Dict[str, float]]:
    """The parameter sets of a sweep: every (E, nu) pair, as dicts for simulate_material."""
    return [{"youngs_modulus": float(E), "poisson_ratio": float(nu), "density": float(density)}
            for E in youngs_moduli for nu in poisson_ratios]


def simulate_material(params: Dict[str, float], *, frames: int = 20, cells: Tuple[int, int, int] = (2, 2, 8),
                      points: int = 2000, threads: int = 1) -> Dict[str, Any]:
    """One run of a material sweep: a 1 x 1 x 4 m bar (box control mesh of `cells`) clamped at
    z = 0 sags under gravity for `frames` frames of 1/30 s, driving `points` dense points by
    modified-BI. params: youngs_modulus (Pa), poisson_ratio, density (kg/m^3). Returns the
    parameters with tip_sag (m, the largest downward displacement of a dense point),
    kinetic_energy and elastic_energy (J) at the last frame, and digest (of the dense positions)."""
    _mbi.set_threads(threads)
    U, T = box_mesh(*cells, size=(1.0, 1.0, 4.0))
    sim = _mbi.Simulator(U, T, youngs_modulus=params["youngs_modulus"], poisson_ratio=params["poisson_ratio"],
                         density=params["density"], dt=1.0 / 30.0, substeps=2, gravity=(0.0, -9.81, 0.0),
                         mass_damping=0.5)
    sim.fix(np.flatnonzero(U[:, 2] == 0.0))
    P = np.random.default_rng(0).uniform(0.0, 1.0, (points, 3)) * (1.0, 1.0, 4.0)
    pipe = _mbi.FramePipeline(U, T, P, sim, method="modified-bi")
    final = pipe.run(frames + 1)[-1]  # frame 0 is the rest pose
    return dict(params, tip_sag=float(-(final[:, 1] - P[:, 1]).min()), kinetic_energy=sim.kinetic_energy(),
                elastic_energy=sim.elastic_energy(), digest=digest(final))


def deform_model(path: str, out_dir: str, *, vertices: int = 150, frames: int = 10, youngs_modulus: float = 2e5,
                 threads: int = 1) -> Dict[str, Any]:
    """One run of a folder of models: a cage of about `vertices` vertices around the model at
    `path` (mbi.cage), clamped on its back (the 15% of the cage with the lowest z), sags under
    gravity for `frames` frames of 1/30 s (a bar of 1000 kg/m^3 and `youngs_modulus` Pa, the
    model's units taken as m); the model's last frame is written to out_dir/<name>.obj with every
    attribute of the file (UVs, groups, materials; normals, which would be stale, are left out). Returns the model's
    name, sizes, the cage's, max_displacement (model units), digest and the OBJ written."""
    _mbi.set_threads(threads)
    mesh = _mbi.read_surface(path)
    U, T = _mbi.cage(mesh.V, mesh.F, vertices=vertices, force_3d=True)
    lo, hi = U.min(0), U.max(0)
    sim = _mbi.Simulator(U, T, youngs_modulus=youngs_modulus, density=1000.0, dt=1.0 / 30.0,
                         gravity=(0.0, -9.81, 0.0), mass_damping=0.5)
    sim.fix(np.flatnonzero(U[:, 2] <= lo[2] + 0.15 * (hi[2] - lo[2])))
    pipe = _mbi.FramePipeline(U, T, mesh.V, sim, method="modified-bi")
    final = pipe.run(frames + 1)[-1]
    name = os.path.splitext(os.path.basename(path))[0]
    out = os.path.join(out_dir, name + ".obj")
    _mbi.write_surface(out, mesh.with_positions(final, N=None))
    return {"model": name, "vertices": int(mesh.V.shape[0]), "cage_vertices": int(U.shape[0]),
            "elements": int(T.shape[0]), "max_displacement": float(np.linalg.norm(final - mesh.V, axis=1).max()),
            "digest": digest(final), "obj": out}


def run_batch(function: Callable[..., Any], items: Iterable[Any], client: Optional[Any] = None,
              **kwargs: Any) -> List[Any]:
    """function(item, **kwargs) for every item, in the order of `items`: one by one in this process
    when client is None, else as tasks of the dask.distributed Client (one task an item)."""
    if client is None:
        return [function(item, **kwargs) for item in items]
    futures = client.map(function, list(items), pure=False, **kwargs)
    gathered: List[Any] = client.gather(futures)
    return gathered
