#!/usr/bin/env python3
"""Writes the VTK XML fixtures of tests/data/vtu/ (see README.md), or converts a run's frames.

    /usr/bin/python3 tests/data/vtu/make.py              the committed fixtures (meshio, and VTK
                                                         itself for the encodings meshio lacks)
    /usr/bin/python3 tests/data/vtu/make.py RUN OUT      mbi run's RUN/control_NNNN.vtk, read and
                                                         written again by meshio as OUT/frame_NNNN.vtu
                                                         (ASCII, base64, zlib in turn) with OUT/run.pvd

Debian's interpreter (/usr/bin/python3) has python3-meshio; the VTK writer is python3-vtk9.
"""
import math
import os
import struct
import sys

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def box():
    """A 2 x 2 x 2-cell box (27 nodes, 48 positive tetrahedra) of irrational extent."""
    h = [0.0, math.sqrt(2) / 4, math.sqrt(2) / 2]
    pts = np.array([[h[i], h[j], 2 * h[k]] for k in range(3) for j in range(3) for i in range(3)])
    node = lambda i, j, k: i + 3 * j + 9 * k
    tets = []
    for i in range(2):
        for j in range(2):
            for k in range(2):
                for axes in [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]:
                    c = [i, j, k]
                    t = [node(*c)]
                    for a in axes:
                        c[a] += 1
                        t.append(node(*c))
                    p = pts[t]
                    if np.linalg.det(np.array([p[1] - p[0], p[2] - p[0], p[3] - p[0]])) < 0:
                        t[2], t[3] = t[3], t[2]
                    tets.append(t)
    return pts, np.array(tets)


def twist(pts, angle):
    """Twisted about the box's vertical axis by `angle` per unit of height, and bent a little."""
    c = pts[:, :2].mean(axis=0)
    out = pts.copy()
    for r, p in enumerate(pts):
        a = angle * p[2]
        x, y = p[0] - c[0], p[1] - c[1]
        out[r, 0] = c[0] + math.cos(a) * x - math.sin(a) * y + 0.05 * angle * p[2] ** 2
        out[r, 1] = c[1] + math.sin(a) * x + math.cos(a) * y
    return out


def write_vtu(path, pts, tets, encoding):
    m = meshio.Mesh(pts, [("tetra", tets)])
    if encoding == "ascii":
        meshio.vtu.write(path, m, binary=False)
    else:
        meshio.vtu.write(path, m, binary=True, compression={"binary": None, "zlib": "zlib", "lzma": "lzma"}[encoding])


def write_pvd(path, names, times):
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n  <Collection>\n')
        for n, t in zip(names, times):
            f.write('    <DataSet timestep="%r" group="" part="0" file="%s"/>\n' % (t, n))
        f.write("  </Collection>\n</VTKFile>\n")


def write_with_vtk(pts, tets):
    """The encodings meshio does not write, by VTK 9's own writer."""
    import vtk

    points = vtk.vtkPoints()
    points.SetDataTypeToDouble()
    for p in pts:
        points.InsertNextPoint(*p)
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points)
    for t in tets:
        ids = vtk.vtkIdList()
        for i in t:
            ids.InsertNextId(int(i))
        grid.InsertNextCell(10, ids)
    variants = {  # name: (appended, base64 appended, zlib, UInt64 headers, big endian)
        "box-vtk-raw.vtu": (True, False, False, False, False),
        "box-vtk-raw-zlib.vtu": (True, False, True, False, False),
        "box-vtk-appended-base64.vtu": (True, True, False, False, False),
        "box-vtk-appended-base64-zlib.vtu": (True, True, True, True, False),
        "box-vtk-binary-zlib-bigendian.vtu": (False, False, True, True, True),
    }
    for name, (appended, b64, zlib, u64, big) in variants.items():
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(os.path.join(HERE, name))
        w.SetInputData(grid)
        if appended:
            w.SetDataModeToAppended()
            w.SetEncodeAppendedData(b64)
        else:
            w.SetDataModeToBinary()
        if zlib:
            w.SetCompressorTypeToZLib()
        else:
            w.SetCompressorTypeToNone()
        if u64:
            w.SetHeaderTypeToUInt64()
        if big:
            w.SetByteOrderToBigEndian()
        assert w.Write() == 1, name


def write_pc2(path, frames):
    with open(path, "wb") as f:
        f.write(b"POINTCACHE2\0" + struct.pack("<iiffi", 1, len(frames[0]), 1.0, 1.0, len(frames)))
        for x in frames:
            f.write(np.asarray(x, "<f4").tobytes())


def write_mdd(path, frames, times, rest=None):
    """MDD as Blender's exporter writes it: big endian; with `rest`, its extra rest frame first."""
    with open(path, "wb") as f:
        f.write(struct.pack(">ii", len(frames), len(frames[0])))
        f.write(np.asarray(times, ">f4").tobytes())
        for x in ([rest] if rest is not None else []) + list(frames):
            f.write(np.asarray(x, ">f4").tobytes())


def sphere(path):
    """A UV sphere of 144 vertices inside the box, for the end-to-end scene (sag.toml)."""
    c, r, n = (0.3535, 0.3535, 0.707), 0.25, 8
    vs, fs = [], []
    for i in range(n + 1):
        th = math.pi * i / n
        for j in range(2 * n):
            ph = math.pi * j / n
            vs.append((c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.sin(th) * math.sin(ph), c[2] + r * math.cos(th)))
    for i in range(n):
        for j in range(2 * n):
            a, b = i * 2 * n + j, i * 2 * n + (j + 1) % (2 * n)
            fs += [(a, a + 2 * n, b + 2 * n), (a, b + 2 * n, b)]
    with open(path, "w") as f:
        f.write("".join("v %r %r %r\n" % v for v in vs) + "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in fs))


def fixtures():
    pts, tets = box()
    sphere(os.path.join(HERE, "sphere.obj"))
    with open(os.path.join(HERE, "box.node"), "w") as f:
        f.write("%d 3 0 0\n" % len(pts) + "".join("%d %r %r %r\n" % (i, *p) for i, p in enumerate(pts)))
    with open(os.path.join(HERE, "box.ele"), "w") as f:
        f.write("%d 4 0\n" % len(tets) + "".join("%d %d %d %d %d\n" % (i, *t) for i, t in enumerate(tets)))
    for enc in ["ascii", "binary", "zlib"]:
        write_vtu(os.path.join(HERE, "box-meshio-%s.vtu" % enc), pts, tets, enc)
    write_with_vtk(pts, tets)
    # a trajectory: three twisted poses, one encoding each, collected by a .pvd (times 0.5 s apart)
    frames = [twist(pts, a) for a in (0.2, 0.4, 0.6)]
    names = []
    for k, (x, enc) in enumerate(zip(frames, ["ascii", "binary", "zlib"])):
        names.append("twist_%04d.vtu" % k)
        write_vtu(os.path.join(HERE, names[-1]), x, tets, enc)
        np.savetxt(os.path.join(HERE, "twist_%04d.txt" % k), x, fmt="%.17g")
    write_pvd(os.path.join(HERE, "twist.pvd"), names, [0.5, 1.0, 1.5])
    write_pc2(os.path.join(HERE, "twist.pc2"), frames)
    write_mdd(os.path.join(HERE, "twist-blender.mdd"), frames, [0.5, 1.0, 1.5], rest=pts)


def convert_run(run, out):
    os.makedirs(out, exist_ok=True)
    names, k = [], 0
    while os.path.exists(os.path.join(run, "control_%04d.vtk" % k)):
        m = meshio.read(os.path.join(run, "control_%04d.vtk" % k))
        names.append("frame_%04d.vtu" % k)
        write_vtu(os.path.join(out, names[-1]), m.points, m.cells_dict["tetra"], ["ascii", "binary", "zlib"][k % 3])
        k += 1
    assert names, "no control_NNNN.vtk in " + run
    write_pvd(os.path.join(out, "run.pvd"), names, [0.1 * i for i in range(len(names))])


if __name__ == "__main__":
    if len(sys.argv) == 3:
        convert_run(sys.argv[1], sys.argv[2])
    else:
        fixtures()
