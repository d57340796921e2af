"""Inside `blender -b --factory-startup`: the pinned nodes of a simulated cage follow an animated
Blender object. An Empty keyed linearly (a velocity and a rotation about x from frame 3 to 9) carries
the pins: the baked model equals `mbi run` of a scene whose kinematic constraint has that motion, at
every frame. An armature's bone keyed with Bezier easing carries them: at every frame the pinned
nodes are where the bone's transform puts them. Following no object is refused.

    blender -b --factory-startup --python follow.py -- <work dir> <mbi executable>
"""
import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import check, evaluated, fail, positions, run_main, select_only  # noqa: E402
from physics import END, FPS, START, mbi_run, start  # noqa: E402

FIRST, LAST, RATE, VELOCITY = 3, 9, 2.0, (0.0, 0.0, 0.5)


def linear(obj):
    for curve in obj.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def empty_handle(center):
    """An Empty at the pins' center moving at VELOCITY and turning about x at RATE from FIRST to LAST."""
    bpy.ops.object.empty_add(location=tuple(center))
    empty = bpy.context.active_object
    empty.keyframe_insert("location", frame=FIRST)
    empty.keyframe_insert("rotation_euler", frame=FIRST)
    seconds = (LAST - FIRST) / FPS
    empty.location = tuple(np.array(center) + np.array(VELOCITY) * seconds)
    empty.rotation_euler.x = RATE * seconds
    empty.keyframe_insert("location", frame=LAST)
    empty.keyframe_insert("rotation_euler", frame=LAST)
    linear(empty)
    return empty


def bone_handle(center):
    """An armature whose bone, keyed with Bezier easing, turns and moves."""
    bpy.ops.object.armature_add(location=tuple(center))
    armature = bpy.context.active_object
    bone = armature.pose.bones["Bone"]
    bone.rotation_mode = "XYZ"
    bone.keyframe_insert("rotation_euler", frame=START)
    bone.keyframe_insert("location", frame=START)
    bone.rotation_euler = (0.0, 0.6, 0.3)
    bone.location = (0.1, 0.2, -0.1)
    bone.keyframe_insert("rotation_euler", frame=END)
    bone.keyframe_insert("location", frame=END)
    return armature


def refused_without_object(cage):
    cage.mbi.pin_motion = "object"
    select_only([cage], cage)
    try:
        bpy.ops.mbi.simulate(directory="//none")
        fail("pins following no object were simulated")
    except RuntimeError as error:
        check("choose the object" in str(error), "following no object is refused: %s" % str(error).strip())


def follows_bone(work, pins, size):
    bpy.ops.wm.open_mainfile(filepath=os.path.join(work, "physics.blend"))
    cage = next(o for o in bpy.data.objects if o.mbi.is_cage)
    U = positions(cage.data)
    armature = bone_handle(U[pins].mean(axis=0))
    cage.mbi.pin_motion, cage.mbi.pin_object, cage.mbi.pin_bone = "object", armature, "Bone"
    select_only([cage], cage)
    check(bpy.ops.mbi.simulate(directory="//bone_cache") == {"FINISHED"}, "the pins follow a bone keyed with easing")
    scene = bpy.context.scene
    worst, moved = 0.0, 0.0
    for frame in range(START, END + 1):
        scene.frame_set(frame)
        bone = armature.pose.bones["Bone"]
        B = np.array(armature.matrix_world) @ np.array(bone.matrix)
        if frame == START:
            B0 = B
        A = B @ np.linalg.inv(B0)
        X = evaluated(cage)
        worst = max(worst, np.abs(X[pins] - (U[pins] @ A[:3, :3].T + A[:3, 3])).max() / size)
        moved = max(moved, np.abs(X[pins] - U[pins]).max() / size)
    check(worst <= 1e-5, "at every frame the pinned nodes are where the bone puts them (%.2e of the size)" % worst)
    check(moved > 0.05, "and they moved (%.3f of the size)" % moved)


def main(work, exe):
    mbi, model, cage, pins, rest, size = start(work)
    refused_without_object(cage)

    center = positions(cage.data)[pins].mean(axis=0)
    empty = empty_handle(center)
    cage.mbi.pin_object = empty
    select_only([cage], cage)
    check(bpy.ops.mbi.simulate() == {"FINISHED"}, "the pins follow an Empty keyed linearly")
    dt = 1.0 / FPS
    motion = ("motion = { twist_axis = [1.0, 0.0, 0.0], twist_center = [%r, %r, %r], twist_rate = %r, "
              "velocity = [%r, %r, %r], start = %r, stop = %r }"
              % (*map(float, center), RATE, *VELOCITY, (FIRST - START) * dt, (LAST - START) * dt))
    expected = mbi_run(mbi, exe, work, model, cage, pins, motion)
    baked = mbi.read_point_cache(bpy.path.abspath(model.modifiers["mbi cache"].filepath)).frames
    error = np.abs(baked - expected).max() / size
    check(error <= 1e-6, "the baked model equals mbi run with the same kinematic motion at every frame (%.2e)"
          % error)
    moved = np.abs(baked[-1] - rest).max() / size
    check(moved > 0.05 and math.isfinite(moved), "the pins carried the model (%.3f of its size)" % moved)
    follows_bone(work, pins, size)
    print("PASS")


if __name__ == "__main__":
    run_main(main)
