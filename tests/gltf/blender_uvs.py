# blender -b --factory-startup --python blender_uvs.py -- ANIM.glb MODEL.obj CACHE.pc2
# Blender's glTF importer reads an animated glTF that mbi wrote from an OBJ: the first frame's
# object has a UV layer, and every loop's (position, UV) is a corner of the OBJ at the point
# cache's first frame, its UV the OBJ's within 1e-7 (Blender turns glTF's v back into the OBJ's),
# every OBJ corner met once. Exit 1 on the first difference.
import struct
import sys

import bpy

anim, obj, cache = sys.argv[sys.argv.index("--") + 1:]


def fail(what):
    print(f"{anim}: {what}")
    sys.exit(1)


# the OBJ's corners (vertex, vt) fan-triangulated, and its texture coordinates
vt, corners = [], []
with open(obj) as f:
    for line in f:
        w = line.split()
        if not w:
            continue
        if w[0] == "vt":
            vt.append((float(w[1]), float(w[2])))
        elif w[0] == "f":
            c = [tuple(int(x) - 1 for x in s.split("/")[:2]) for s in w[1:]]
            for k in range(1, len(c) - 1):
                corners += [c[0], c[k], c[k + 1]]

with open(cache, "rb") as f:
    b = f.read()
points = struct.unpack_from("<i", b, 16)[0]
first = struct.unpack_from(f"<{3 * points}f", b, 32)  # the first frame

bpy.ops.wm.read_factory_settings(use_empty=True)
# import_shading='SMOOTH' avoids the importer's np.bool (gone in numpy 1.24)
bpy.ops.import_scene.gltf(filepath=anim, import_shading="SMOOTH")
meshes = [o for o in bpy.context.scene.objects if o.type == "MESH" and o.name.startswith("frame_0000")]
if not meshes:
    fail("no object frame_0000")
unmatched = list(range(len(corners)))
loops = 0
for o in meshes:
    me = o.data
    if not me.uv_layers:
        fail(f"{o.name}: no UV layer")
    uv = me.uv_layers[0].data
    for loop in me.loops:
        loops += 1
        co = o.matrix_world @ me.vertices[loop.vertex_index].co
        p = (co.x, co.z, -co.y)  # Blender's z up back to glTF's y up
        u, v = uv[loop.index].uv
        found = None
        for i in unmatched:
            vi, ti = corners[i]
            if all(abs(p[d] - first[3 * vi + d]) <= 1e-6 for d in range(3)) and \
                    abs(u - vt[ti][0]) <= 1e-7 and abs(v - vt[ti][1]) <= 1e-7:
                found = i
                break
        if found is None:
            fail(f"{o.name}: loop {loop.index}: position {p}, UV ({u}, {v}) is no corner of the OBJ")
        unmatched.remove(found)
if unmatched:
    fail(f"{len(unmatched)} corners of the OBJ not imported ({loops} loops)")
print(f"{anim}: {loops} loops: UVs as the OBJ's")
