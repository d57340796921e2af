"""Inside `blender -b --factory-startup`: the add-on cages and binds a model, the cage is animated by a
keyframed shape key, and Blender's evaluated model (and a second mesh bound in the same bind) equals
`mbi deform` on the same data (to 1e-6 of its size), before and after saving and reopening the .blend;
an empty mesh is refused.

    blender -b --factory-startup --python live_cage.py -- <work dir> <mbi executable>
"""
import os
import subprocess
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import check, fail, positions, select_only, world  # noqa: E402

FRAMES = (1, 6, 11)


def make_model():
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0, location=(0.4, -0.2, 0.1))
    model = bpy.context.active_object
    model.name = "model"
    model.scale = (1.6, 0.8, 0.6)
    bpy.context.view_layer.update()  # matrix_world follows the scale
    return model


def make_second():
    """A second mesh inside the first (a cube of side 0.4), bound to the same cage in the same bind."""
    bpy.ops.mesh.primitive_cube_add(size=0.4, location=(0.7, -0.2, 0.1), rotation=(0.2, 0.3, 0.0))
    second = bpy.context.active_object
    second.name = "second"
    bpy.context.view_layer.update()
    return second


def twist(U, size):
    """A twist about z and a bend, large enough that a wrong deformation shows."""
    c = U.mean(axis=0)
    R = U - c
    angle = 3.0 * R[:, 2] / size
    x = R[:, 0] * np.cos(angle) - R[:, 1] * np.sin(angle)
    y = R[:, 0] * np.sin(angle) + R[:, 1] * np.cos(angle)
    z = R[:, 2] + 0.5 * size * (R[:, 0] / size) ** 2
    return np.stack([x, y, z], axis=1) + c


def animate_cage(cage):
    U = positions(cage.data)
    cage.shape_key_add(name="Basis", from_mix=False)
    pose = cage.shape_key_add(name="pose", from_mix=False)
    pose.data.foreach_set("co", twist(U, np.ptp(U, axis=0).max()).astype(np.float32).ravel())
    pose.value = 0.0
    pose.keyframe_insert("value", frame=FRAMES[0])
    pose.value = 1.0
    pose.keyframe_insert("value", frame=FRAMES[-1])


def blender_frame(model, cage, frame=None):
    """The model's and the cage's evaluated positions at a frame (None: as they are), in world (= cage) space."""
    if frame is not None:
        bpy.context.scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    P = world(model, positions(model.evaluated_get(depsgraph).data))
    X = positions(cage.evaluated_get(depsgraph).data)
    return P, X


def mbi_deform(mbi, exe, work, cage, rest_model, X, tag):
    base = os.path.join(work, "cage")
    mbi.write_tetgen(base, positions(cage.data), np.asarray(cage.data["mbi_tets"].to_list()).reshape(-1, 4))
    np.savetxt(os.path.join(work, "x_%s.txt" % tag), X, fmt="%.17g")
    mbi.write_points(os.path.join(work, "model.txt"), rest_model)
    out = os.path.join(work, "out_%s.txt" % tag)
    run = subprocess.run([exe, "deform", "--control", base, "--deformed", os.path.join(work, "x_%s.txt" % tag),
                          "--mesh", os.path.join(work, "model.txt"), "--out", out, "--force"],
                         capture_output=True, text=True)
    if run.returncode != 0:
        fail("mbi deform: " + run.stderr)
    return mbi.read_points(out)


def compare(mbi, exe, work, bound, cage, tag):
    """Each bound (model, rest, size) equals `mbi deform` at FRAMES and moved."""
    for model, rest_model, size in bound:
        moved = 0.0
        for frame in FRAMES:
            P, X = blender_frame(model, cage, frame)
            expected = mbi_deform(mbi, exe, work, cage, rest_model, X, "%s%d" % (tag, frame))
            error = np.abs(P - expected).max() / size
            check(error <= 1e-6, "%s frame %d: Blender's evaluated %s equals mbi deform (%.2e of its size)"
                  % (tag, frame, model.name, error))
            moved = max(moved, np.abs(P - rest_model).max() / size)
        check(moved > 0.05, "%s: %s followed the cage (moved %.3f of its size)" % (tag, model.name, moved))


def edit_in_place(mbi, exe, work, model, cage, rest_model, size):
    """The cage's pose changed without a frame change: the model follows at the next update."""
    keys = cage.data.shape_keys
    keys.animation_data_clear()
    before, _ = blender_frame(model, cage)
    keys.key_blocks["pose"].value = 0.5
    bpy.context.view_layer.update()
    P, X = blender_frame(model, cage)
    expected = mbi_deform(mbi, exe, work, cage, rest_model, X, "edit")
    check(np.abs(P - before).max() / size > 0.01, "editing the cage's key moved the model")
    error = np.abs(P - expected).max() / size
    check(error <= 1e-6, "after an edit in place the model equals mbi deform (%.2e of its size)" % error)


def bad_input():
    mesh = bpy.data.meshes.new("empty")
    empty = bpy.data.objects.new("empty", mesh)
    bpy.context.collection.objects.link(empty)
    select_only([empty], empty)
    count = len(bpy.data.objects)
    try:
        bpy.ops.mbi.cage()
        fail("an empty mesh was caged")
    except RuntimeError as error:
        check("has no faces" in str(error), "an empty mesh is refused: %s" % str(error).strip())
    check(len(bpy.data.objects) == count, "no cage object is left behind")

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, radius=0.3, location=(3.0, 0.0, 0.0))
    bpy.ops.mbi.cage(vertices=60)
    small_cage = bpy.context.active_object
    check(small_cage.mbi.is_cage, "the new cage is the active object")
    model = bpy.data.objects["model"]
    cage = model.mbi.cage
    select_only([model, small_cage], small_cage)
    try:
        bpy.ops.mbi.bind()
        fail("a cage that does not enclose the model was bound")
    except RuntimeError as error:
        message = str(error).strip()
        check("does not fit in the cage" in message and "outside" in message,
              "a cage that does not enclose the model is refused: %s" % message)
    check(model.mbi.cage == cage and model.modifiers[0].name == "mbi" and len(model.modifiers) == 1,
          "the refused bind leaves the earlier one as it was")


def unbind(model, rest_model):
    """Unbind removes what the add-on made: the modifier, the attribute, the node group; the model is at rest."""
    group = model.modifiers["mbi"].node_group
    check(group is not None and "mbi_position" in model.data.attributes and model.data.shape_keys is None,
          "a bound model carries the attribute and the modifier, no shape key")
    check(np.abs(world(model, positions(model.data)) - rest_model).max() == 0, "its mesh vertices stay at rest")
    second = bpy.data.objects["second"]
    select_only([model], model)
    check(bpy.ops.mbi.unbind() == {"FINISHED"}, "the unbind operator ran")
    check("mbi" not in model.modifiers and "mbi_position" not in model.data.attributes
          and second.modifiers["mbi"].node_group == group, "unbind removed the modifier and the attribute, "
          "and kept the node group the second mesh uses")
    select_only([second], second)
    bpy.ops.mbi.unbind()
    check(not any(g.get("mbi_live") for g in bpy.data.node_groups), "unbinding the last mesh removed the node group")
    P, _ = blender_frame(model, model, 11)
    check(model.mbi.cage is None and np.abs(P - rest_model).max() == 0, "the unbound model is at rest at frame 11")


def main(work, exe):
    addon_utils.enable("mbi_blender", default_set=True)
    from mbi_blender import module
    mbi = module.load()
    model = make_model()
    rest_model = world(model, positions(model.data))
    size = np.linalg.norm(np.ptp(rest_model, axis=0))
    select_only([model], model)
    check(bpy.ops.mbi.cage(vertices=150) == {"FINISHED"}, "the cage operator ran")
    cage = next(o for o in bpy.data.objects if o.mbi.is_cage)
    tets = np.asarray(cage.data["mbi_tets"].to_list()).reshape(-1, 4)
    check(len(tets) > 0 and tets.max() < len(cage.data.vertices), "the cage holds %d tetrahedra" % len(tets))
    second = make_second()
    bound = [(model, rest_model, size), (second, world(second, positions(second.data)), 0.4 * np.sqrt(3))]
    select_only([model, second, cage], cage)
    check(bpy.ops.mbi.bind(method="modified-bi") == {"FINISHED"}, "the bind operator ran on two meshes")
    check(model.mbi.cage == cage and second.mbi.cage == cage, "both meshes are bound to the cage")
    animate_cage(cage)
    compare(mbi, exe, work, bound, cage, "live")

    path = os.path.join(work, "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    model, cage = bpy.data.objects["model"], next(o for o in bpy.data.objects if o.mbi.is_cage)
    reopened = np.asarray(cage.data["mbi_tets"].to_list()).reshape(-1, 4)
    check(np.array_equal(reopened, tets), "the tetrahedra survive save and reopen")
    check(model.mbi.cage == cage, "the model is still bound after reopening")
    compare(mbi, exe, work, [(model, rest_model, size), (bpy.data.objects["second"],) + bound[1][1:]], cage,
            "reopened")
    edit_in_place(mbi, exe, work, model, cage, rest_model, size)
    bad_input()
    unbind(model, rest_model)
    print("PASS")


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    try:
        main(*args)
    except Exception as error:  # noqa: BLE001 - any escape is a failure with its message, not Blender's exit 0
        import traceback
        traceback.print_exc()
        fail("%s: %s" % (type(error).__name__, error))
    sys.exit(0)
