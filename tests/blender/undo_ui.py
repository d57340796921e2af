"""In Blender's UI (under Xvfb: undo needs a window): undoing a bind leaves the model unbound at
rest, redo binds it again at the frame's positions, and undoing a cage edit brings the model back
with the cage.

    xvfb-run -a blender --factory-startup --python undo_ui.py -- <work dir> <mbi executable>
"""
import os
import sys

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import live_cage as lc  # noqa: E402


def evaluated(model):
    return lc.world(model, lc.positions(model.evaluated_get(bpy.context.evaluated_depsgraph_get()).data))


def scenario(work, exe):
    from mbi_blender import module
    mbi = module.load()
    model = lc.make_model()
    rest = lc.world(model, lc.positions(model.data))
    size = np.linalg.norm(np.ptp(rest, axis=0))
    lc.select_only([model], model)
    bpy.ops.mbi.cage(vertices=150)
    cage = next(o for o in bpy.data.objects if o.mbi.is_cage)
    cage_name = cage.name  # undo and redo replace the Python objects
    lc.animate_cage(cage)
    bpy.context.scene.frame_set(6)
    bpy.ops.ed.undo_push(message="cage")  # operators run from a script push no step: the UI's steps, by hand
    lc.select_only([model, cage], cage)
    bpy.ops.mbi.bind()
    bpy.ops.ed.undo_push(message="bind")
    bound = evaluated(model)
    lc.check(np.abs(bound - rest).max() / size > 0.01, "bound at frame 6, the model is deformed")

    bpy.ops.ed.undo()
    model = bpy.data.objects["model"]
    lc.check(model.mbi.cage is None, "undoing the bind unbinds the model")
    lc.check(np.abs(evaluated(model) - rest).max() == 0, "and leaves it at rest")
    bpy.ops.ed.redo()
    model, cage = bpy.data.objects["model"], bpy.data.objects[cage_name]
    lc.check(model.mbi.cage == cage and bpy.context.scene.frame_current == 6, "redo binds it again at frame 6")
    P, X = lc.blender_frame(model, cage)
    expected = lc.mbi_deform(mbi, exe, work, cage, rest, X, "redo")
    lc.check(np.abs(P - expected).max() / size <= 1e-6, "after redo the model equals mbi deform")

    keys = cage.data.shape_keys
    keys.animation_data_clear()
    bpy.ops.ed.undo_push(message="still")
    keys.key_blocks["pose"].value = 0.2
    bpy.context.view_layer.update()
    bpy.ops.ed.undo_push(message="edit")
    edited = evaluated(model)
    lc.check(np.abs(edited - P).max() / size > 0.01, "editing the cage moved the model")
    bpy.ops.ed.undo()
    model = bpy.data.objects["model"]
    lc.check(np.abs(evaluated(model) - P).max() / size <= 1e-6, "undoing the edit brings the model back with the cage")


def run(work, exe):
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    code = 0
    try:
        addon_utils.enable("mbi_blender", default_set=True)
        with bpy.context.temp_override(window=window, area=area):
            scenario(work, exe)
        print("PASS")
    except SystemExit as stop:
        code = stop.code
    except Exception as error:  # noqa: BLE001 - any escape is a failure with its message
        import traceback
        traceback.print_exc()
        print("FAIL: %s: %s" % (type(error).__name__, error))
        code = 1
    os._exit(code)  # the UI's quit would write a session recovery file and exit 0


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    bpy.app.timers.register(lambda: run(*args), first_interval=0.5)  # once the window exists
