"""Inside `blender -b --factory-startup`: a cage simulated by the add-on (mbi's FEM: gravity, damping,
nodes pinned by a vertex group, scene at 24 fps) and its bound model baked over frames 1..13; the
baked model equals `mbi run` of a scene with the same data (dense.pc2), frame by frame; the cage's
cache plays its motion; a cancelled simulation leaves no cache.

    blender -b --factory-startup --python physics.py -- <work dir> <mbi executable>
"""
import os
import subprocess
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import check, evaluated, fail, positions, run_main, select_only, write_scene  # noqa: E402

START, END, FPS = 1, 13, 24
MATERIAL = dict(young=3e4, poisson=0.4, density=1000.0, mass_damping=0.5)


def setup():
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
    model = bpy.context.active_object
    model.name = "model"
    model.scale = (2.0, 0.5, 0.5)
    bpy.ops.object.transform_apply(scale=True)  # world = local: the scene file takes the same numbers
    bpy.ops.mbi.cage(vertices=200)
    cage = bpy.context.active_object
    U = positions(cage.data)
    pins = np.flatnonzero(U[:, 0] < U[:, 0].min() + 0.15 * np.ptp(U[:, 0]))
    group = cage.vertex_groups.new(name="pin")
    group.add(pins.tolist(), 1.0, "REPLACE")
    for name, value in MATERIAL.items():
        setattr(cage.mbi, name, value)
    cage.mbi.pin_group = "pin"
    select_only([model, cage], cage)
    bpy.ops.mbi.bind()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = FPS, START, END
    return model, cage, pins


def mbi_run(mbi, exe, work, model, cage, pins, motion=""):
    """The same simulation as a scene for `mbi run` (pinned nodes fixed, or moved by motion): its dense.pc2."""
    pinned = '[[constraints]]\ntype = "%s"\nselect = { indices = %s }\n%s' % (
        "kinematic" if motion else "fixed", pins.tolist(), motion)
    path = write_scene(mbi, work, "blender-physics", model, cage, MATERIAL, 1.0 / FPS, END - START, pinned)
    out = os.path.join(work, "run-kinematic" if motion else "run")
    run = subprocess.run([exe, "run", path, "--out", out, "--force", "--quiet"], capture_output=True, text=True)
    check(run.returncode == 0, "mbi run of the same scene: %s" % run.stderr.strip()[-500:])
    return mbi.read_point_cache(os.path.join(out, "dense.pc2")).frames


def rigid_pins(mbi, exe, work, pins):
    """The saved scene again, its pinned nodes moved by a rigid motion set in the cage's panel keys: the baked
    model equals `mbi run` with a kinematic constraint, and the pinned nodes follow the motion's formula."""
    bpy.ops.wm.open_mainfile(filepath=os.path.join(work, "physics.blend"))
    model, cage = bpy.data.objects["model"], next(o for o in bpy.data.objects if o.mbi.is_cage)
    rest = evaluated(model)
    size = np.linalg.norm(np.ptp(rest, axis=0))
    U = positions(cage.data)
    center, axis, rate, velocity, start, stop = U[pins].mean(axis=0), (1.0, 0.0, 0.0), 2.0, (0.0, 0.0, 0.6), 0.1, 0.4
    s = cage.mbi
    s.pin_group = ""
    s.pin_motion = "rigid"
    select_only([cage], cage)
    try:
        bpy.ops.mbi.simulate(directory="//rigid_cache")
        fail("a rigid motion without a pinned group was simulated")
    except RuntimeError as error:
        check("no pinned group" in str(error), "a rigid motion without pinned nodes is refused: %s"
              % str(error).strip())
    s.pin_group = "pin"
    s.pin_velocity, s.pin_rate, s.pin_axis, s.pin_center = velocity, rate, axis, center
    s.pin_start, s.pin_stop = start, stop
    check(bpy.ops.mbi.simulate(directory="//rigid_cache") == {"FINISHED"}, "the simulate operator ran, pins moving")
    motion = ("motion = { twist_axis = [%r, %r, %r], twist_center = [%r, %r, %r], twist_rate = %r, "
              "velocity = [%r, %r, %r], start = %r, stop = %r }" % (*axis, *map(float, center), rate, *velocity,
                                                                   start, stop))
    expected = mbi_run(mbi, exe, work, model, cage, pins, motion)
    baked = mbi.read_point_cache(bpy.path.abspath(model.modifiers["mbi cache"].filepath)).frames
    error = np.abs(baked - expected).max() / size
    check(error <= 1e-6, "with moving pins the baked model equals mbi run's at every frame (%.2e)" % error)
    held = mbi.read_point_cache(os.path.join(work, "run", "dense.pc2")).frames
    check(np.abs(baked - held).max() / size > 0.05, "and differs from the run with held pins (%.3f of its size)"
          % (np.abs(baked - held).max() / size))
    t = (END - START) / FPS
    moved = min(max(t, start), stop) - start
    angle = rate * moved
    c, sn = np.cos(angle), np.sin(angle)
    R = np.array([[1, 0, 0], [0, c, -sn], [0, sn, c]])
    formula = center + np.array(velocity) * moved + (U[pins] - center) @ R.T
    X = evaluated(cage, END)
    error = np.abs(X[pins] - formula).max() / size
    check(error <= 1e-5, "the pinned nodes at the last frame are where the rigid motion puts them (%.2e)" % error)
    check(np.abs(X[pins] - U[pins]).max() / size > 0.05, "and they moved (%.3f of the size)"
          % (np.abs(X[pins] - U[pins]).max() / size))


def start(work):
    """The add-on enabled, the scene set up and saved as physics.blend: mbi, model, cage, pins, the model's
    evaluated rest positions and its size."""
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    model, cage, pins = setup()
    rest = evaluated(model)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(work, "physics.blend"))
    return mbi, model, cage, pins, rest, np.linalg.norm(np.ptp(rest, axis=0))


def main(work, exe):
    mbi, model, cage, pins, rest, size = start(work)
    from mbi_blender import physics

    job = physics.simulate_job(bpy.context.scene, cage, START, END, "//mbi_cache")
    for _ in range(3):
        next(job)
    job.close()
    folder = os.path.join(work, "mbi_cache")
    left = os.listdir(folder)
    check(not left and "mbi cache" not in cage.modifiers and "mbi cache" not in model.modifiers,
          "a simulation cancelled after 3 frames leaves no cache (folder holds %s)" % left)

    select_only([cage], cage)
    check(bpy.ops.mbi.simulate() == {"FINISHED"}, "the simulate operator ran frames %d..%d" % (START, END))
    check("mbi cache" in cage.modifiers and model.mbi.baked, "the cage plays its cache, the model is baked")
    expected = mbi_run(mbi, exe, work, model, cage, pins)
    check(len(expected) == END - START + 1, "mbi run wrote %d frames" % len(expected))
    baked = mbi.read_point_cache(bpy.path.abspath(model.modifiers["mbi cache"].filepath)).frames
    error = np.abs(baked - expected).max() / size
    check(error <= 1e-6, "the baked model equals mbi run's dense.pc2 at every frame (%.2e of its size)" % error)
    sag = np.abs(baked[-1] - rest).max() / size
    check(sag > 0.02, "the model moved under gravity (%.3f of its size)" % sag)
    for frame in (START, 7, END):
        P = evaluated(model, frame)
        error = np.abs(P - expected[frame - START]).max() / size
        check(error <= 1e-6, "frame %d: Blender plays the baked model (%.2e)" % (frame, error))
    X = evaluated(cage, END)
    check(np.array_equal(X[pins], positions(cage.data)[pins]) and np.abs(X - positions(cage.data)).max() > 0,
          "the cage's cache moves it, its pinned nodes held")
    rigid_pins(mbi, exe, work, pins)
    print("PASS")


if __name__ == "__main__":
    run_main(main)
