"""Draws the add-on's panel in Blender's UI (under Xvfb) and saves the sidebar as a PNG.

    blender -b --factory-startup --python-expr "import bpy; bpy.ops.wm.save_as_mainfile(filepath='/tmp/empty.blend')"
    MBI_PYTHON_DIR=build/release/python xvfb-run -a -s "-screen 0 1280x860x24" blender --factory-startup \\
        --enable-event-simulate /tmp/empty.blend --python blender/panel_screenshot.py -- docs/blender-panel.png

A bound ico sphere in a 200-node cage bent by a shape key, at frame 8, the discontinuity table
computed; the 3D view's sidebar on the tab "mbi" is cropped out of the area's screenshot. A file
given on the command line keeps the splash screen away; Blender 3.4 cannot choose a sidebar tab
from Python, so a simulated click (--enable-event-simulate) on the tab strip (the fourth tab, "mbi") does.
"""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mbi_blender  # noqa: E402


def scene(window, area):
    with bpy.context.temp_override(window=window, area=area):
        bpy.ops.object.select_all(action="SELECT")
        bpy.ops.object.delete()
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
        model = bpy.context.active_object
        model.name = "model"
        model.scale = (1.8, 0.6, 0.6)
        bpy.ops.mbi.cage(vertices=200)
        cage = bpy.context.active_object
        bpy.ops.mbi.bind()
        U = np.empty(len(cage.data.vertices) * 3, dtype=np.float32)
        cage.data.vertices.foreach_get("co", U)
        U = U.reshape(-1, 3)
        cage.shape_key_add(name="Basis", from_mix=False)
        key = cage.shape_key_add(name="bend", from_mix=False)
        X = U.copy()
        X[:, 2] += 0.25 * U[:, 0] ** 2
        key.data.foreach_set("co", X.ravel())
        key.value = 0.0
        key.keyframe_insert("value", frame=1)
        key.value = 1.0
        key.keyframe_insert("value", frame=15)
        bpy.context.scene.frame_set(8)
        bpy.ops.object.select_all(action="DESELECT")
        model.select_set(True)
        bpy.context.view_layer.objects.active = model
        bpy.ops.mbi.discontinuity()


def show_sidebar(area):
    space = area.spaces.active
    space.show_region_ui = True
    space.overlay.show_floor = True
    area.regions[-1].tag_redraw()


def click_tab(window, area, y_from_top):
    """A simulated click on the sidebar's tab strip (its right edge), y pixels below the region's top."""
    region = next(r for r in area.regions if r.type == "UI")
    x, y = region.x + region.width - 8, region.y + region.height - y_from_top
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    window.event_simulate(type="LEFTMOUSE", value="PRESS", x=x, y=y)
    window.event_simulate(type="LEFTMOUSE", value="RELEASE", x=x, y=y)


def save(window, area, path):
    region = next(r for r in area.regions if r.type == "UI")
    whole = path + ".area.png"
    with bpy.context.temp_override(window=window, area=area):
        bpy.ops.screen.screenshot_area(filepath=whole)
    image = bpy.data.images.load(whole)
    w, h = image.size
    pixels = np.array(image.pixels[:], dtype=np.float32).reshape(h, w, 4)
    x0, y0 = region.x - area.x, region.y - area.y
    crop = pixels[y0:y0 + region.height, x0:x0 + region.width]
    out = bpy.data.images.new("panel", crop.shape[1], crop.shape[0], alpha=False)
    out.pixels[:] = crop.ravel()
    out.filepath_raw, out.file_format = path, "PNG"
    out.save()
    os.remove(whole)
    print("saved %s (%d x %d)" % (path, crop.shape[1], crop.shape[0]))


def run(path):
    window = bpy.context.window_manager.windows[0]
    area = max((a for a in window.screen.areas if a.type == "VIEW_3D"), key=lambda a: a.width * a.height)
    mbi_blender.register()
    scene(window, area)
    show_sidebar(area)
    bpy.app.timers.register(lambda: click_tab(window, area, 155), first_interval=0.5)  # once the sidebar is drawn
    bpy.app.timers.register(lambda: finish(window, area, path), first_interval=2.0)


def finish(window, area, path):
    code = 0
    try:
        save(window, area, path)
    except Exception as error:  # noqa: BLE001
        print("FAIL: %s" % error)
        code = 1
    os._exit(code)


if __name__ == "__main__":
    target = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
    bpy.app.timers.register(lambda: run(target), first_interval=0.5)  # once the window exists
