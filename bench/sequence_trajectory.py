#!/usr/bin/env python3
"""A 200-frame control trajectory for scripts/bench-sequence.sh: the nodes of DIR/cage.node
twisted about the vertical axis (up to 90 degrees) and swayed, as DIR/traj.pc2 and as 200 text
files DIR/frame_NNNN.txt (the inputs of the 200 single-pose calls).

    python3 bench/sequence_trajectory.py DIR [FRAMES]
"""
import math
import os
import struct
import sys

folder = sys.argv[1]
frames = int(sys.argv[2]) if len(sys.argv) > 2 else 200
with open(os.path.join(folder, "cage.node")) as f:
    rows = [l.split() for l in f if l.strip() and not l.startswith("#")]
n = int(rows[0][0])
U = [tuple(float(x) for x in r[1:4]) for r in rows[1 : n + 1]]
lo = [min(p[k] for p in U) for k in range(3)]
hi = [max(p[k] for p in U) for k in range(3)]
c = [(lo[k] + hi[k]) / 2 for k in range(3)]
h = hi[1] - lo[1]


def pose(t):
    out = []
    for x, y, z in U:
        s = (y - lo[1]) / h  # 0 at the bottom, 1 at the top
        a = 0.5 * math.pi * t * s
        dx, dz = x - c[0], z - c[2]
        out.append((c[0] + math.cos(a) * dx - math.sin(a) * dz + 0.1 * h * math.sin(2 * math.pi * t) * s * s,
                    y, c[2] + math.sin(a) * dx + math.cos(a) * dz))
    return out


with open(os.path.join(folder, "traj.pc2"), "wb") as pc2:
    pc2.write(b"POINTCACHE2\0" + struct.pack("<iiffi", 1, n, 0.0, 1.0, frames))
    for k in range(frames):
        X = pose(k / max(frames - 1, 1))
        pc2.write(struct.pack("<%df" % (3 * n), *[v for p in X for v in p]))
        with open(os.path.join(folder, "frame_%04d.txt" % k), "w") as f:
            f.write("".join("%.9g %.9g %.9g\n" % p for p in X))
