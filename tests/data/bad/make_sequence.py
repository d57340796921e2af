#!/usr/bin/env python3
"""Writes the files of the sequence cases of the bad-input corpus, tests/data/bad/sequence/
(cases: sequence.cases), from the fixtures of tests/data/vtu/ (the 27-node box and its poses).

Run from anywhere: python3 tests/data/bad/make_sequence.py. The files are committed.
"""
import os
import shutil
import struct

here = os.path.dirname(os.path.abspath(__file__))
out = os.path.join(here, "sequence")
vtu = os.path.join(here, "..", "vtu")
os.makedirs(out, exist_ok=True)


def w(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(out, name), "wb") as f:
        f.write(data)


def read(name):
    with open(os.path.join(vtu, name), "rb") as f:
        return f.read()


def copy(src, dst):
    shutil.copyfile(os.path.join(vtu, src), os.path.join(out, dst))


pc2 = read("twist.pc2")  # 27 points x 3 samples
mdd = read("twist-blender.mdd")
# --- caches: header and size disagree, wrong node count, a NaN in frame 2
w("truncated.pc2", pc2[:-12])
w("truncated.mdd", mdd[: 8 + 12 + 27 * 12 * 2 + 100])
w("26-points.pc2", pc2[:16] + struct.pack("<i", 26) + pc2[20:28] + struct.pack("<i", 3) + pc2[32 : 32 + 26 * 12 * 3])
nan = bytearray(pc2)
nan[32 + 2 * 27 * 12 + 5 * 12 + 4 : 32 + 2 * 27 * 12 + 5 * 12 + 8] = struct.pack("<f", float("nan"))
w("nan-frame-2.pc2", bytes(nan))
# --- numbered text frames: frame 2 has a bad number, frame 1 of another series 26 rows
for k in range(3):
    copy("twist_%04d.txt" % k, "good_%d.txt" % k)
lines = read("twist_0002.txt").decode().splitlines(True)
lines[4] = "0.1 nan 0.3\n"
w("badnum_0.txt", read("twist_0000.txt"))
w("badnum_1.txt", read("twist_0001.txt"))
w("badnum_2.txt", "".join(lines))
w("short_0.txt", read("twist_0000.txt"))
w("short_1.txt", "".join(read("twist_0001.txt").decode().splitlines(True)[:26]))
# --- .vtu frames: frame 1 cut inside its data
copy("twist_0000.vtu", "cut_0000.vtu")
v = read("twist_0001.vtu").decode()
at = v.index('format="binary">') + 40
w("cut_0001.vtu", v[:at] + v[at + 300 :])
# --- .pvd naming a file that does not exist
w("missing.pvd", '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
  '    <DataSet timestep="0" file="good_0.txt"/>\n    <DataSet timestep="1" file="gone_1.vtu"/>\n'
  "  </Collection>\n</VTKFile>\n")
# --- a .vtu compressed with LZMA (meshio writes it; only zlib is read)
v = read("box-meshio-zlib.vtu").decode().replace("vtkZLibDataCompressor", "vtkLZMADataCompressor")
w("lzma.vtu", v)
