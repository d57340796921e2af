"""Inside `blender -b --factory-startup`: bake a bound model (a cage animated by a keyframed shape key) to
a PC2 point cache with a Mesh Cache modifier; Blender's evaluated model then equals the live one (1e-6
of its size) at frames of the baked range (scene at 25 fps, range 3..12), also in a second Blender with
neither the add-on nor mbi; un-bake restores the live path; a cancelled bake, a bake failing at a frame
and a relative folder of an unsaved file leave no cache.

    blender -b --factory-startup --python bake.py -- <work dir> <mbi executable>
"""
import os
import subprocess
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import bound_sphere, check, evaluated, fail, pose_key, positions, run_main, select_only  # noqa: E402

START, END, CHECKED = 3, 12, (3, 7, 12)


def setup():
    model, cage = bound_sphere(4, location=(0.4, -0.2, 0.1), scale=(1.6, 0.8, 0.6))
    U = positions(cage.data)
    c = U.mean(axis=0)
    angle = 2.0 * (U[:, 2] - c[2]) / np.ptp(U[:, 2])
    X = U.copy()
    X[:, 0] = c[0] + (U[:, 0] - c[0]) * np.cos(angle) - (U[:, 1] - c[1]) * np.sin(angle)
    X[:, 1] = c[1] + (U[:, 0] - c[0]) * np.sin(angle) + (U[:, 1] - c[1]) * np.cos(angle)
    pose = pose_key(cage, X)
    for frame, value in ((1, 0.0), (14, 1.0)):
        pose.value = value
        pose.keyframe_insert("value", frame=frame)
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = 25, START, END
    return model, cage


def no_cache_left(model, folder, what):
    left = os.listdir(folder) if os.path.isdir(folder) else []
    check(not left and "mbi cache" not in model.modifiers and not model.mbi.baked,
          "%s: no cache file, no modifier, not baked (folder holds %s)" % (what, left))


def refused(what, call, words):
    try:
        call()
    except RuntimeError as error:
        check(words in str(error), "%s is refused: %s" % (what, str(error).strip()))
        return
    fail("%s was not refused" % what)


def failing_bakes(model, cage, folder):
    from mbi_blender import bake
    job = bake.bake_job(bpy.context.scene, [model], START, END, folder)
    for _ in range(4):
        next(job)
    job.close()  # what Esc does
    no_cache_left(model, folder, "a bake cancelled after 4 frames")
    check(bpy.context.scene.frame_current == 1, "the cancelled bake restored the current frame")

    def break_cage(scene, *_):
        if scene.frame_current == 8 and "break" not in cage.modifiers:
            cage.modifiers.new("break", "SUBSURF")
    bpy.app.handlers.frame_change_pre.append(break_cage)
    refused("a bake whose live path fails at frame 8", lambda: bpy.ops.mbi.bake(directory=folder), "frame 8")
    bpy.app.handlers.frame_change_pre.remove(break_cage)
    cage.modifiers.remove(cage.modifiers["break"])
    no_cache_left(model, folder, "the failed bake")


def play_elsewhere(work, blend):
    """The saved file in a second Blender whose user folder has no add-on and whose Python has no mbi."""
    env = {k: v for k, v in os.environ.items() if k not in ("MBI_PYTHON_DIR", "PYTHONPATH")}
    env["HOME"] = os.path.join(work, "bare")
    os.makedirs(env["HOME"], exist_ok=True)
    out = os.path.join(work, "played.npy")
    run = subprocess.run([bpy.app.binary_path, "-b", "--factory-startup", blend, "--python",
                          os.path.join(os.path.dirname(__file__), "playback.py"), "--", out]
                         + [str(f) for f in CHECKED], env=env, capture_output=True, text=True)
    print(run.stdout[-2000:], run.stderr[-2000:])
    check(run.returncode == 0 and "PLAYED" in run.stdout, "a Blender without the add-on and mbi played the file")
    return np.load(out)


def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    model, cage = setup()
    size = np.linalg.norm(np.ptp(evaluated(model), axis=0))
    live = np.array([evaluated(model, f) for f in CHECKED])
    check(np.abs(live[-1] - live[0]).max() / size > 0.05, "the live model moves over the range")
    bpy.context.scene.frame_set(1)
    select_only([model], model)
    refused("a relative cache folder of an unsaved file", lambda: bpy.ops.mbi.bake(), "save the .blend first")
    folder = os.path.join(work, "mbi_cache")
    failing_bakes(model, cage, folder)

    blend = os.path.join(work, "baked.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    check(bpy.ops.mbi.bake() == {"FINISHED"}, "the bake operator ran (folder //mbi_cache)")
    modifier = model.modifiers["mbi cache"]
    check(model.modifiers[0] == modifier and modifier.time_mode == "FRAME" and modifier.frame_start == START,
          "Mesh Cache modifier first, FRAME mode, frame_start %d" % modifier.frame_start)
    cache = mbi.read_point_cache(bpy.path.abspath(modifier.filepath))
    check(cache.frames.shape == (END - START + 1, len(model.data.vertices), 3) and cache.start_frame == START,
          "the PC2 holds %d frames of %d points from frame %g" % (*cache.frames.shape[:2], cache.start_frame))
    check(not [f for f in os.listdir(os.path.dirname(bpy.path.abspath(modifier.filepath))) if "partial" in f],
          "no temporary file is left")
    baked = np.array([evaluated(model, f) for f in CHECKED])
    error = np.abs(baked - live).max() / size
    check(error <= 1e-6, "baked frames %s equal the live ones (%.2e of the size)" % (CHECKED, error))
    bpy.ops.wm.save_mainfile()
    played = play_elsewhere(work, blend)
    error = np.abs(played - live).max() / size
    check(error <= 1e-6, "without the add-on and mbi, frames %s equal the live ones (%.2e)" % (CHECKED, error))

    bpy.ops.wm.open_mainfile(filepath=blend)
    model = bpy.data.objects["model"]
    select_only([model], model)
    check(bpy.ops.mbi.unbake() == {"FINISHED"} and "mbi cache" not in model.modifiers and not model.mbi.baked,
          "un-bake removed the modifier")
    unbaked = np.array([evaluated(model, f) for f in CHECKED])
    error = np.abs(unbaked - live).max() / size
    check(error <= 1e-6, "after un-bake the live path gives the same frames (%.2e)" % error)
    print("PASS")


if __name__ == "__main__":
    run_main(main)
