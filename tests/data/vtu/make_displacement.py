#!/usr/bin/env python3
"""Writes a FEniCS-like series into OUT: the rest box (box.node, box.ele) with a displacement.

    /usr/bin/python3 tests/data/vtu/make_displacement.py OUT

OUT/disp_000K.vtu and OUT/disp_000K.vtk: the rest points with the point fields "displacement"
(27 x 3) and "temperature" (27 x 1); OUT/baked_000K.vtu: the same motion in the points, no field.
Frames K = 0, 1, 2 in meshio's encodings in turn (.vtu: ASCII, base64, zlib; .vtk: ASCII, binary).
"""
import math
import os
import sys

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def read_box():
    with open(os.path.join(HERE, "box.node")) as f:
        rows = [line.split() for line in f if line.strip() and not line.startswith("#")]
    pts = np.array([[float(x) for x in r[1:4]] for r in rows[1:]])
    with open(os.path.join(HERE, "box.ele")) as f:
        rows = [line.split() for line in f if line.strip() and not line.startswith("#")]
    tets = np.array([[int(x) for x in r[1:5]] for r in rows[1:]])
    return pts, tets


def displacement(pts, k):
    """A smooth motion: a twist about the box's long axis and a bend, growing with k."""
    a = 0.2 * (k + 1)
    c = pts - pts.mean(axis=0)
    z = pts[:, 2] / pts[:, 2].max()
    d = np.zeros_like(pts)
    d[:, 0] = (math.cos(a * z.mean()) - 1) * c[:, 0] - a * z * c[:, 1] + 0.05 * k * z ** 2
    d[:, 1] = a * z * c[:, 0] + 0.01 * k
    d[:, 2] = 0.02 * k * c[:, 0]
    return d


def main(out):
    os.makedirs(out, exist_ok=True)
    pts, tets = read_box()
    for k in range(3):
        d = displacement(pts, k)
        fields = {"temperature": 300 + pts[:, 2], "displacement": d}
        enc = ["ascii", "binary", "zlib"][k]
        kw = dict(binary=False) if enc == "ascii" else dict(binary=True, compression=None if enc == "binary" else "zlib")
        meshio.vtu.write(os.path.join(out, "disp_%04d.vtu" % k), meshio.Mesh(pts, [("tetra", tets)], point_data=fields), **kw)
        meshio.vtu.write(os.path.join(out, "baked_%04d.vtu" % k), meshio.Mesh(pts + d, [("tetra", tets)]), **kw)
        meshio.vtk.write(os.path.join(out, "disp_%04d.vtk" % k), meshio.Mesh(pts, [("tetra", tets)], point_data=fields),
                         binary=k % 2 == 1)


if __name__ == "__main__":
    main(sys.argv[1])
