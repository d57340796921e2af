"""Scenes run from Python: mbi.run_scene, `mbi run` without the command line."""
import json
import os
from typing import Any, Dict, Literal, Optional, Union

from . import _mbi

PathLike = Union[str, "os.PathLike[str]"]


def summary_dict(s: _mbi.Summary) -> Dict[str, float]:
    """An mbi.Summary as {"mean", "std", "max"}."""
    return {"mean": s.mean, "std": s.std, "max": s.max}


def table_dict(t: _mbi.DiscontinuityTable) -> Dict[str, Any]:
    """An mbi.DiscontinuityTable as a dict of plain numbers (the shape of metrics.json's "last_disc")."""
    out: Dict[str, Any] = {"bi": summary_dict(t.bi), "modified_bi": summary_dict(t.modified_bi), "ratio": summary_dict(t.ratio),
           "faces": t.faces, "e_vibr": t.e_vibr, "e_disc": t.e_disc, "e_total": t.e_total}
    if t.phong is not None and t.phong_ratio is not None:
        out["phong"] = summary_dict(t.phong)
        out["phong_ratio"] = summary_dict(t.phong_ratio)
    return out


def run_scene(path: PathLike, out: Optional[PathLike] = None, *, frames: int = 0, mesh: Optional[PathLike] = None,
              method: Optional[Literal["bi", "modified-bi", "phong"]] = None,
              gpu: Optional[Literal["auto", "on", "off"]] = None, force: bool = False,
              force_3d: bool = False) -> Dict[str, Any]:
    """Runs the scene file `path` headless, as `mbi run` does, writing its outputs into the folder
    `out` (default out/<scene name>). frames: 0 = the scene's; mesh: a dense model replacing the
    scene's; method: "bi", "modified-bi" or "phong" replacing the scene's; gpu: "auto", "on" or
    "off" (None: the scene's). Returns the run's summary, a dict: scene, out_dir, frames (completed),
    failed and message (a simulation step that failed: outputs up to the last good frame are kept),
    evaluator, outside_points, warnings, last_disc (the last frame's discontinuity table) and
    metrics (metrics.json as the run wrote it, or None when the scene writes none).
    Bad input raises mbi.Error (mbi.FileError for a file) before anything is written."""
    r: Dict[str, Any] = _mbi._run_scene(os.fspath(path), None if out is None else os.fspath(out), frames,
                        None if mesh is None else os.fspath(mesh), method, gpu, force, force_3d)
    r["last_disc"] = table_dict(r.pop("last_table"))
    metrics = os.path.join(r["out_dir"], "metrics.json")
    r["metrics"] = None
    if os.path.isfile(metrics):
        with open(metrics, encoding="utf-8") as f:
            r["metrics"] = json.load(f)
    return r
