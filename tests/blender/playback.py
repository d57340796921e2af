"""A baked .blend played without the add-on and without mbi: the model's evaluated positions at frames.

    blender -b --factory-startup <file.blend> --python playback.py -- <out.npy> <frame>...
"""
import importlib.util
import sys

import addon_utils
import bpy
import numpy as np

args = sys.argv[sys.argv.index("--") + 1:]
if importlib.util.find_spec("mbi") is not None or addon_utils.check("mbi_blender")[1]:
    print("FAIL: mbi or the add-on is reachable here")
    sys.exit(1)
model = bpy.data.objects["model"]
frames = []
for frame in map(int, args[1:]):
    bpy.context.scene.frame_set(frame)
    mesh = model.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    M = np.array(model.matrix_world)
    frames.append(co.reshape(-1, 3) @ M[:3, :3].T + M[:3, 3])
np.save(args[0], np.array(frames))
print("PLAYED %d frames" % len(frames))
sys.exit(0)
