#!/usr/bin/env python3
"""Writes the files of the readers' bad-input corpus, tests/data/bad/io/ (cases: io.cases).

Run from anywhere: python3 tests/data/bad/make_io.py. The files are committed; this script
says how each was made (several are binary, and a few have huge header counts in a few bytes).
"""
import os
import struct

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "io")
os.makedirs(here, exist_ok=True)


def w(name, data):
    if isinstance(data, str):
        data = data.encode()
    assert len(data) < 20000, name
    with open(os.path.join(here, name), "wb") as f:
        f.write(data)


BOM = b"\xef\xbb\xbf"
# --- good partners: a tetrahedron control mesh, its deformed positions, a dense model inside
TET = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
NODE = "4 3 0 0\n" + "".join("%d %g %g %g\n" % (i, *p) for i, p in enumerate(TET))
ELE = "1 4 0\n0 0 1 2 3\n"
w("ok.node", NODE)
w("ok.ele", ELE)
w("ok-x.txt", "0 0 0\n1.1 0 0\n0 1 0\n0 0 1.2\n")
DENSE = [(0.1, 0.1, 0.1), (0.3, 0.1, 0.1), (0.1, 0.3, 0.1), (0.1, 0.1, 0.3)]
TRIS = [(1, 3, 2), (1, 2, 4), (2, 3, 4), (1, 4, 3)]


def obj(vs, fs, extra=""):
    return "".join("v %s %s %s\n" % v for v in vs) + "".join("f %s %s %s\n" % f for f in fs) + extra


w("ok.obj", obj(DENSE, TRIS))

# --- OBJ
w("obj-nan.obj", obj([(0.1, 0.1, 0.1), ("nan", 0.1, 0.1)] + DENSE[2:], TRIS))
w("obj-inf.obj", obj(DENSE[:2] + [(0.1, "-inf", 0.1)] + DENSE[3:], TRIS))
w("obj-1e308.obj", obj(DENSE[:3] + [(0.1, 0.1, "1e308")], TRIS))
w("obj-1e309.obj", obj(DENSE[:3] + [(0.1, 0.1, "1e309")], TRIS))
w("obj-index-out-of-range.obj", obj(DENSE, TRIS[:3] + [(1, 4, 5)]))
w("obj-index-zero.obj", obj(DENSE, [(0, 1, 2)]))
w("obj-relative-before-first.obj", obj(DENSE, [(-1, -2, -9)]))
w("obj-huge-index.obj", obj(DENSE, [(1, 2, 99999999999)]))
w("obj-two-corners.obj", obj(DENSE, []) + "f 1 2\n")
w("obj-vt-out-of-range.obj", obj(DENSE, []) + "vt 0 0\nf 1/1 2/2 3/1\n")
w("obj-vn-out-of-range.obj", obj(DENSE, []) + "vn 0 0 1\nf 1//1 2//1 3//3\n")
w("obj-corner-four-numbers.obj", obj(DENSE, []) + "f 1/1/1/1 2 3\n")
w("obj-missing-coordinate.obj", "v 0.1 0.1\n")
w("obj-garbage-coordinate.obj", "v 0.1 0x1p3 0.1\n")
w("obj-bom-nan.obj", BOM + obj([("nan", 0.1, 0.1)] + DENSE[1:], TRIS).encode())
w("obj-crlf-bad-index.obj", obj(DENSE, [(1, 2, 7)]).replace("\n", "\r\n"))
w("obj-cr-only-bad-index.obj", obj(DENSE, [(1, 2, 8)]).replace("\n", "\r"))
w("obj-binary.obj", bytes(range(256)) * 4)
w("obj-empty.obj", "")
w("obj-only-comments.obj", "# nothing\n\n   \t\n# here\n")

# --- OFF
OFF_BODY = "".join("%g %g %g\n" % v for v in DENSE) + "".join("3 %d %d %d\n" % tuple(i - 1 for i in t) for t in TRIS)
w("off-bad-magic.off", "FOO\n4 4 0\n" + OFF_BODY)
w("off-huge-counts.off", "OFF\n2147483647 2147483647 0\n" + OFF_BODY)
w("off-negative-count.off", "OFF\n-4 4 0\n" + OFF_BODY)
w("off-count-overflow.off", "OFF\n99999999999999999999 4 0\n" + OFF_BODY)
w("off-truncated.off", "OFF\n4 4 0\n" + OFF_BODY[:40])
w("off-face-index.off", "OFF\n4 1 0\n" + "".join("%g %g %g\n" % v for v in DENSE) + "3 0 1 4\n")
w("off-nan.off", "OFF\n4 4 0\n" + OFF_BODY.replace("0.3 0.1 0.1", "0.3 nan 0.1"))
w("off-binary.off", "OFF BINARY\n4 4 0\n")
w("off-face-size.off", "OFF\n4 1 0\n" + "".join("%g %g %g\n" % v for v in DENSE) + "5 0 1 2\n")
# homogeneous 4OFF: x y z w per vertex, the point is (x, y, z) / w
OFF4_FACES = "".join("3 %d %d %d\n" % tuple(i - 1 for i in t) for t in TRIS)
w("off4-half.off", "4OFF\n4 4 0\n" + "".join("%g %g %g 0.5\n" % tuple(c / 2 for c in v) for v in DENSE) + OFF4_FACES)
w("off4-w-zero.off", "4OFF\n4 4 0\n" + "".join("%g %g %g %g\n" % (*v, 0 if i == 2 else 1) for i, v in enumerate(DENSE)) + OFF4_FACES)
w("off4-w-nan.off", "4OFF\n4 4 0\n" + "".join("%g %g %g %s\n" % (*v, "nan" if i == 1 else "1") for i, v in enumerate(DENSE)) + OFF4_FACES)
w("off4-missing-w.off", "4OFF\n4 4 0\n" + OFF_BODY)
w("off-n-dimensional.off", "nOFF\n4\n4 4 0\n" + "".join("%g %g %g 0\n" % v for v in DENSE) + OFF4_FACES)


# --- PLY
def ply_header(fmt, elements):
    h = "ply\nformat %s 1.0\n" % fmt
    for name, count, props in elements:
        h += "element %s %s\n" % (name, count)
        h += "".join("property %s\n" % p for p in props)
    return (h + "end_header\n").encode()


VXYZ = ["float x", "float y", "float z"]
FACE = ["list uchar int vertex_indices"]


def ply_bin(vs, fs, vtype="f", e="<"):
    b = b"".join(struct.pack(e + "3" + vtype, *v) for v in vs)
    return b + b"".join(struct.pack(e + "B3i", 3, *[i - 1 for i in f]) for f in fs)


# 2^31 - 1 items with no properties in a 160-byte file: refused at once, not looped over
h = ply_header("binary_little_endian", [("vertex", 4, VXYZ), ("nothing", 2147483647, [])])
w("ply-no-properties-2e31.ply", (h + ply_bin(DENSE, [])).ljust(160, b"\0"))
w("ply-huge-vertex-count.ply", ply_header("binary_little_endian", [("vertex", 2147483647, VXYZ)]) + ply_bin(DENSE, []))
w("ply-count-overflow.ply", ply_header("ascii", [("vertex", 4294967296, VXYZ)]))
w("ply-negative-count.ply", ply_header("ascii", [("vertex", -1, VXYZ)]))
w("ply-ascii-huge-count.ply", ply_header("ascii", [("vertex", 2000000000, VXYZ)]) + b"0 0 0\n")
full = ply_header("binary_little_endian", [("vertex", 4, VXYZ), ("face", 4, FACE)]) + ply_bin(DENSE, TRIS)
# one name, two properties: the reader would keep the last, the writer fill the first
PLY_ASCII_BODY = "".join("%g %g %g\n" % v for v in DENSE) + "".join("3 %d %d %d\n" % tuple(i - 1 for i in t) for t in TRIS)
w("ply-two-x.ply", ply_header("ascii", [("vertex", 4, ["float x", "float y", "float z", "float x"]), ("face", 4, FACE)]) +
  ("".join("%g %g %g %g\n" % (*v, v[0]) for v in DENSE) + PLY_ASCII_BODY.split("\n", 4)[4]).encode())
w("ply-two-vertex-elements.ply", ply_header("ascii", [("vertex", 4, VXYZ), ("vertex", 0, VXYZ), ("face", 4, FACE)]) +
  PLY_ASCII_BODY.encode())
w("ply-two-index-lists.ply", ply_header("ascii", [("vertex", 4, VXYZ), ("face", 4, FACE + ["list uchar int vertex_index"])]) +
  ("".join("%g %g %g\n" % v for v in DENSE) + "".join("3 %d %d %d 3 0 1 2\n" % tuple(i - 1 for i in t) for t in TRIS)).encode())
# integer positions (a 10-unit model in int, uchar): deformed positions are written as double
INT_DENSE = [(1, 1, 1), (3, 1, 1), (1, 3, 1), (1, 1, 3)]
w("ply-int-positions.ply", ply_header("ascii", [("vertex", 4, ["int x", "int y", "int z"]), ("face", 4, FACE)]) +
  ("".join("%d %d %d\n" % v for v in INT_DENSE) + PLY_ASCII_BODY.split("\n", 4)[4]).encode())
w("ply-uchar-positions.ply", ply_header("binary_little_endian", [("vertex", 4, ["uchar x", "uchar y", "uchar z"]), ("face", 4, FACE)]) +
  b"".join(struct.pack("<3B", *v) for v in INT_DENSE) + b"".join(struct.pack("<B3i", 3, *[i - 1 for i in f]) for f in TRIS))
w("int-x10.txt", "0 0 0\n11 0 0\n0 10 0\n0 0 12\n")
w("int.node", "4 3 0 0\n" + "".join("%d %g %g %g\n" % (i, *(10 * c for c in p)) for i, p in enumerate(TET)))
w("int.ele", ELE)
w("ply-truncated.ply", full[:-7])
w("ply-missing-end-header.ply", b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n")
w("ply-unknown-format.ply", ply_header("binary_middle_endian", [("vertex", 4, VXYZ)]))
w("ply-face-index.ply", ply_header("ascii", [("vertex", 4, VXYZ), ("face", 1, FACE)]) +
  ("".join("%g %g %g\n" % v for v in DENSE) + "3 0 1 4\n").encode())
w("ply-binary-face-index.ply", ply_header("binary_big_endian", [("vertex", 4, VXYZ), ("face", 1, FACE)]) +
  ply_bin(DENSE, [(1, 2, 99)], e=">"))
w("ply-list-count-huge.ply", ply_header("binary_little_endian", [("vertex", 4, VXYZ), ("face", 1, ["list uint int vertex_indices"])]) +
  ply_bin(DENSE, []) + struct.pack("<I", 4000000000) + struct.pack("<3i", 0, 1, 2))
w("ply-nan.ply", ply_header("binary_little_endian", [("vertex", 4, VXYZ)]) + ply_bin(DENSE[:3] + [(0.1, float("nan"), 0.1)], []))
w("ply-1e308.ply", ply_header("binary_little_endian", [("vertex", 4, ["double x", "double y", "double z"])]) +
  ply_bin(DENSE[:1] + [(1e308, 0.1, 0.1)] + DENSE[2:], [], vtype="d"))
w("ply-no-xyz.ply", ply_header("ascii", [("vertex", 1, ["float x", "float y"])]) + b"0 0\n")
w("ply-float-list-count.ply", ply_header("ascii", [("vertex", 1, VXYZ), ("face", 0, ["list float int vertex_indices"])]) + b"0 0 0\n")
w("ply-not-ply.ply", b"PLY?\n" + full)

# --- STL
def stl_bin(tris, count=None, corners=None):
    b = b"bad-input corpus".ljust(80, b"\0") + struct.pack("<I", len(tris) if count is None else count)
    for t in tris:
        b += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *p) for p in t) + b"\0\0"
    return b


STL_T = [[DENSE[i - 1] for i in t] for t in TRIS]
w("stl-wrong-count.stl", stl_bin(STL_T, count=5))
w("stl-huge-count.stl", stl_bin(STL_T[:1], count=0xFFFFFFFF))
w("stl-nan.stl", stl_bin([STL_T[0], [(0.1, 0.1, float("nan")), DENSE[1], DENSE[2]]]))


def stl_ascii(tris, bad=None):
    s = "solid corpus\n"
    for t in tris:
        s += " facet normal 0 0 1\n  outer loop\n" + "".join("   vertex %s %s %s\n" % p for p in t) + "  endloop\n endfacet\n"
    return s + "endsolid corpus\n"


w("stl-inf-ascii.stl", stl_ascii(STL_T[:1] + [[(0.1, "inf", 0.1), DENSE[1], DENSE[2]]]))
w("stl-two-vertices.stl", stl_ascii([STL_T[0], STL_T[1][:2]]))
w("stl-unclosed-facet.stl", stl_ascii(STL_T).rsplit("  endloop", 1)[0])
w("stl-too-short.stl", b"\0" * 40)

# --- point lists (deformed positions and dense points)
w("pts-ragged.txt", "0 0 0\n1 0\n0 1 0\n0 0 1\n")
w("pts-nan.txt", "0 0 0\n1 0 0\n0 NaN 0\n0 0 1\n")
w("pts-1e308.txt", "0 0 0\n1 0 0\n0 1 0\n0 0 -1e308\n")
w("pts-garbage.txt", "0 0 0\n1 0 0\n0 1 0\n0 0 1O\n")
w("pts-too-few.txt", "0 0 0\n1 0 0\n0 1 0\n")
w("pts-bom-crlf-nan.txt", BOM + b"0 0 0\r\n1 0 0\r\nnan 1 0\r\n0 0 1")


# --- TetGen (control meshes: BASE.node + BASE.ele)
def tg(base, node=NODE, ele=ELE):
    w(base + ".node", node)
    w(base + ".ele", ele)


tg("tg-huge-count", node="2147483647 3 0 0\n0 0 0 0\n")
tg("tg-negative-count", node="-4 3 0 0\n")
tg("tg-bad-dimension", node="4 4 0 0\n" + NODE.split("\n", 1)[1])
tg("tg-index", ele="1 4 0\n0 0 1 2 4\n")
tg("tg-ele-huge-count", ele="2147483647 4 0\n0 0 1 2 3\n")
tg("tg-zero-volume", node="4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 1 1 0\n")
tg("tg-repeated-vertex", ele="1 4 0\n0 0 1 2 2\n")
tg("tg-nan", node=NODE.replace("3 0 0 1", "3 0 0 nan"))
tg("tg-1e308", node=NODE.replace("3 0 0 1", "3 0 0 1e308"))
tg("tg-numbering", node=NODE.replace("\n2 ", "\n7 "))
tg("tg-nodes-per-element", ele="1 5 0\n0 0 1 2 3 3\n")
tg("tg-truncated-ele", ele="3 4 0\n0 0 1 2 3\n")
tg("tg-bom-crlf-index", node=(BOM + NODE.replace("\n", "\r\n").encode()), ele="1 4 0\r\n0 0 1 2 9\r\n")

# --- Gmsh
MSH22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n"
w("msh-huge-node-count.msh", MSH22.replace("$Nodes\n4\n", "$Nodes\n2147483647\n"))
w("msh-bad-version.msh", MSH22.replace("2.2 0 8", "3.0 0 8"))
w("msh-unknown-node-tag.msh", MSH22.replace("1 2 3 4\n$End", "1 2 3 9\n$End"))
w("msh-nan.msh", MSH22.replace("4 0 0 1\n", "4 0 0 nan\n"))
w("msh-1e308.msh", MSH22.replace("4 0 0 1\n", "4 0 0 1e308\n"))
w("msh-no-format.msh", MSH22.split("$EndMeshFormat\n", 1)[1])
w("msh-unclosed-section.msh", MSH22.replace("$Elements", "$PhysicalNames\n1\n3 1 \"x\"\n$Elements"))
w("msh-element-count.msh", MSH22.replace("$Elements\n1\n", "$Elements\n2\n"))
w("msh-flat-triangles-not-planar.msh", MSH22.replace("1 4 2 0 1 1 2 3 4", "1 2 2 0 1 1 2 4"))
w("msh-41-huge-blocks.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n2147483647 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n")
w("msh-binary-truncated.msh", b"$MeshFormat\n2.2 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n$Nodes\n4\n" +
  struct.pack("<i3d", 1, 0, 0, 0) + struct.pack("<i3d", 2, 1, 0, 0))
w("msh-zero-volume.msh", MSH22.replace("4 0 0 1\n", "4 1 1 0\n"))

# --- legacy VTK
VTK = "# vtk DataFile Version 3.0\ncorpus\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n"
w("vtk-huge-points.vtk", VTK.replace("POINTS 4", "POINTS 2147483647"))
w("vtk-bad-index.vtk", VTK.replace("4 0 1 2 3", "4 0 1 2 4"))
w("vtk-not-vtk.vtk", VTK.replace("# vtk", "# VTK"))
w("vtk-nan.vtk", VTK.replace("0 0 1\nCELLS", "0 0 nan\nCELLS"))
w("vtk-no-tetrahedra.vtk", VTK.replace("CELL_TYPES 1\n10", "CELL_TYPES 1\n9"))
w("vtk-polydata.vtk", VTK.replace("UNSTRUCTURED_GRID", "POLYDATA"))
w("vtk-types-count.vtk", VTK.replace("CELL_TYPES 1\n10", "CELL_TYPES 2\n10 10"))
w("vtk-huge-cell-size.vtk", VTK.replace("CELLS 1 5", "CELLS 1 2147483647"))

# --- scenes (mbi run)
SCENE = 'name = "corpus"\n[dense]\nbuiltin = "cylinder"\n[control]\nbuiltin = "box"\n[simulation]\nframes = 2\n'
w("scene-nested-arrays.toml", SCENE + "x = " + "[" * 5000 + "]" * 5000 + "\n")
w("scene-nested-inline-tables.toml", SCENE + "x = " + "{a=" * 3000 + "1" + "}" * 3000 + "\n")
w("scene-nested-17.toml", SCENE + "x = " + "[" * 17 + "]" * 17 + "\n")
w("scene-unknown-key.toml", SCENE + "framez = 3\n")
w("scene-wrong-type.toml", SCENE.replace("frames = 2", 'frames = "two"'))
w("scene-syntax-error.toml", SCENE + "[simulation\n")
w("scene-unknown-table.toml", SCENE + "[renderer]\nx = 1\n")
w("scene-binary.toml", bytes(range(256)))
w("scene-dense-bad-obj.toml", 'name = "corpus"\n[dense]\npath = "obj-nan.obj"\n[control]\nbuiltin = "box"\n')
w("scene-dense-missing.toml", 'name = "corpus"\n[dense]\npath = "no-such-model.obj"\n[control]\nbuiltin = "box"\n')
# keys that would do nothing: refused
DRAG = ('name = "corpus"\nmode = "drag"\n[dense]\nbuiltin = "paper-bar"\n[control]\nbuiltin = "box"\n'
        '[[drags]]\nvertex = 0\nkeys = [[0, 0, 0, 0]]\n')
w("scene-drag-pokes.toml", DRAG + "[[pokes]]\nat = [0.5, 0.5, 0.5]\nforce = [1, 0, 0]\n")
w("scene-drag-constraints.toml", DRAG + '[[constraints]]\ntype = "fixed"\nselect = { indices = [0] }\n')
# a single tetrahedron as control mesh: no interior face
w("scene-one-tet.toml", 'name = "corpus"\n[dense]\npath = "ok.obj"\n[control]\npath = "ok.node"\n[simulation]\nframes = 2\n')
# a dense model with a vertex no face uses, Loop-subdivided
w("unused-vertex.obj", obj(DENSE + [(0.2, 0.2, 0.2)], TRIS))
w("scene-subdivide-unused.toml", 'name = "corpus"\nmode = "drag"\n[dense]\npath = "unused-vertex.obj"\nsubdivide = 1\n'
  '[control]\nbuiltin = "box"\ncells = [2, 2, 2]\n[[drags]]\nvertex = 0\nkeys = [[0, 0, 0, 0]]\n')
print("wrote", len(os.listdir(here)), "files to", here)
