"""mbi.run_scene against `mbi run`: the same scene gives the same files and the same metrics
(every field but the clocks), and its summary is the run's; bad scenes raise naming the file."""
import json
import os
import subprocess

import numpy as np
import pytest

import mbi
import meshes

SCENES = os.path.join(os.environ.get("MBI_SOURCE_DIR", ""), "scenes")
MBI = os.environ.get("MBI_EXE")
# under ASan: a 20-vertex dense model (--mesh), not the cylinder, and no pictures
SMALL = os.environ.get("MBI_SANITIZED") == "1"


def without_clocks(x):
    """metrics.json without what depends on the clock or the machine's memory."""
    if isinstance(x, dict):
        return {k: without_clocks(v) for k, v in x.items()
                if not k.endswith("_ms") and k not in ("rss_kb", "timings_ms", "scene_file")}
    if isinstance(x, list):
        return [without_clocks(v) for v in x]
    return x


@pytest.mark.skipif(not MBI or not os.path.exists(MBI), reason="the mbi command line is not built")
@pytest.mark.parametrize("scene", ["cantilever", "drag"])
def test_run_scene_equals_mbi_run(tmp_path, scene):
    path = os.path.join(SCENES, scene + ".toml")
    if SMALL:
        path = meshes.scene_without_pictures(path, tmp_path)
    mesh = meshes.bar_surface(str(tmp_path / "bar.obj")) if SMALL else None
    summary = mbi.run_scene(path, tmp_path / "py", frames=3, gpu="off", mesh=mesh)
    subprocess.run([MBI, "run", path, "--out", str(tmp_path / "cli"), "--frames", "3", "--gpu", "off", "--quiet"]
                   + (["--mesh", mesh] if mesh else []), check=True, capture_output=True)
    with open(tmp_path / "cli" / "metrics.json") as f:
        cli = json.load(f)
    assert without_clocks(summary["metrics"]) == without_clocks(cli)
    for name in ("dense.pc2", "control_0003.vtk"):
        if (tmp_path / "cli" / name).exists():
            assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert summary["frames"] == 3 and not summary["failed"] and summary["scene"] == scene
    assert summary["last_disc"]["faces"] == cli["last_disc"]["faces"]
    assert summary["last_disc"]["bi"]["max"] == pytest.approx(cli["last_disc"]["bi"]["max"], rel=1e-12)


def test_bad_scenes_name_the_file(tmp_path):
    with pytest.raises(mbi.Error, match="nope.toml"):
        mbi.run_scene(tmp_path / "nope.toml", tmp_path / "out")
    bad = tmp_path / "bad.toml"
    with open(os.path.join(SCENES, "cantilever.toml")) as f:
        bad.write_text(f.read().replace("young = 2e5", 'young = "soft"'))
    with pytest.raises(mbi.Error, match=r"bad.toml:\d+: .*young"):
        mbi.run_scene(bad, tmp_path / "out")
    with pytest.raises(ValueError, match="method: unknown value"):
        mbi.run_scene(os.path.join(SCENES, "cantilever.toml"), tmp_path / "out", method="linear")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("frames", [-1, -2**31, 1_000_001])
def test_frames_out_of_range_are_refused_before_anything_is_written(tmp_path, frames):
    with pytest.raises(mbi.Error, match=r"frames = %d: give 1 to 1000000 frames, or 0" % frames):
        mbi.run_scene(os.path.join(SCENES, "drag.toml"), tmp_path / "out", frames=frames)
    assert not (tmp_path / "out").exists()
