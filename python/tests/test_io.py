"""The file readers and writers: known values read from small files of every format, every
writer read back (with the surface's attributes: UVs, groups, materials, PLY properties), and
errors that name the file (mbi.FileError, an OSError) or the argument (ValueError)."""
import numpy as np
import pytest

import mbi

QUAD_OBJ = """mtllib quad.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 0.5
vt 0 0.5
vn 0 0 1
g quad
usemtl red
f 1/1/1 2/2/1 3/3/1 4/4/1
"""

QUAD_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)

TET_NODE = "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n"
TET_ELE = "2 4 0\n1 1 2 3 4\n2 2 3 4 5\n"
TETS = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
NODES = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)


def records(path, tag):
    """The numbers of every `tag` line of a text file (vt, v, ...)."""
    return [[float(x) for x in line.split()[1:]] for line in open(path) if line.startswith(tag + " ")]


def test_obj_known_values_and_attributes_written_back(tmp_path):
    src = tmp_path / "quad.obj"
    src.write_text(QUAD_OBJ)
    mesh = mbi.read_surface(src)
    np.testing.assert_array_equal(mesh.V, QUAD_V)
    np.testing.assert_array_equal(mesh.F, [[0, 1, 2], [0, 2, 3]])  # fan-triangulated
    assert mesh.polygons == [[0, 1, 2, 3]] and mesh.has_attributes
    np.testing.assert_array_equal(mesh.N, np.tile([0, 0, 1.0], (4, 1)))
    out = tmp_path / "moved.obj"
    mbi.write_surface(out, mesh.with_positions(mesh.V * 2))
    text = out.read_text()
    assert "mtllib quad.mtl" in text and "usemtl red" in text and "g quad" in text
    assert records(out, "vt") == records(src, "vt")
    back = mbi.read_surface(out)
    np.testing.assert_array_equal(back.V, QUAD_V * 2)
    assert back.polygons == [[0, 1, 2, 3]] and back.N is None


def test_off_stl_and_points_known_values(tmp_path):
    (tmp_path / "q.off").write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    off = mbi.read_surface(tmp_path / "q.off")
    np.testing.assert_array_equal(off.V, QUAD_V)
    assert off.polygons == [[0, 1, 2, 3]]
    facet = "facet normal 0 0 1\nouter loop\nvertex {}\nvertex {}\nvertex {}\nendloop\nendfacet\n"
    (tmp_path / "q.stl").write_text("solid q\n" + facet.format("0 0 0", "1 0 0", "1 1 0")
                                    + facet.format("0 0 0", "1 1 0", "0 1 0") + "endsolid q\n")
    stl = mbi.read_surface(tmp_path / "q.stl")  # shared corners merged, in order of appearance
    np.testing.assert_array_equal(stl.V, QUAD_V[[0, 1, 2, 3]])
    np.testing.assert_array_equal(stl.F, [[0, 1, 2], [0, 2, 3]])
    (tmp_path / "p.xyz").write_text("# points\n1 2 3\n4, 5, 6\n")
    np.testing.assert_array_equal(mbi.read_points(tmp_path / "p.xyz"), [[1, 2, 3], [4, 5, 6]])
    P = np.random.default_rng(0).standard_normal((7, 3))
    mbi.write_points(tmp_path / "q.txt", P)
    np.testing.assert_array_equal(mbi.read_points(tmp_path / "q.txt"), P)  # %.17g: bit for bit


def test_ply_keeps_every_property_and_encoding(tmp_path):
    (tmp_path / "c.ply").write_text(
        "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty float quality\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0 255 0.5\n1 0 0 128 1.5\n0 1 0 7 2.5\n3 0 1 2\n")
    mesh = mbi.read_surface(tmp_path / "c.ply")
    np.testing.assert_array_equal(mesh.V, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    mbi.write_surface(tmp_path / "d.ply", mesh.with_positions(mesh.V + 1))
    text = (tmp_path / "d.ply").read_text()
    assert "property uchar red" in text and "property float quality" in text and "comment made by hand" in text
    assert "128 1.5" in text
    mbi.write_surface(tmp_path / "e.ply", mesh, encoding="binary")
    assert b"binary_little_endian" in (tmp_path / "e.ply").read_bytes()[:200]
    np.testing.assert_array_equal(mbi.read_surface(tmp_path / "e.ply").V, mesh.V)


@pytest.mark.parametrize("ext", [".obj", ".off", ".ply", ".stl"])
def test_every_surface_writer_reads_back(tmp_path, ext):
    U, T = mbi.box_mesh(2, 1, 1)
    F = mbi.boundary_faces(U, T)
    V = U + 0.01 * np.random.default_rng(1).standard_normal(U.shape)
    path = tmp_path / ("s" + ext)
    mbi.write_surface(path, V, F)
    back = mbi.read_surface(path)
    if ext == ".stl":  # float32 triangles, vertices merged in order of first use
        assert back.F.shape == F.shape
        np.testing.assert_allclose(back.V[back.F], V[F], atol=1e-6)
    else:
        np.testing.assert_array_equal(back.V, V)
        np.testing.assert_array_equal(back.F, F)


def test_control_meshes_of_every_format(tmp_path):
    (tmp_path / "m.node").write_text(TET_NODE)
    (tmp_path / "m.ele").write_text(TET_ELE)
    U, T = mbi.read_control_mesh(tmp_path / "m")
    np.testing.assert_array_equal(U, NODES)
    np.testing.assert_array_equal(T, TETS)
    np.testing.assert_array_equal(mbi.read_positions(tmp_path / "m.node"), NODES)
    gmsh = ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n" + "".join(
        f"{i + 1} {' '.join(str(v) for v in p)}\n" for i, p in enumerate(NODES)) +
        "$EndNodes\n$Elements\n2\n1 4 2 0 1 1 2 3 4\n2 4 2 0 1 2 3 4 5\n$EndElements\n")
    (tmp_path / "m.msh").write_text(gmsh)
    g = mbi.read_control_mesh(tmp_path / "m.msh")
    np.testing.assert_array_equal(g.U, NODES)
    np.testing.assert_array_equal(g.T, TETS)
    mbi.write_vtk(tmp_path / "m.vtk", NODES, TETS, point_vectors=NODES * 0.5)
    v = mbi.read_control_mesh(tmp_path / "m.vtk")
    np.testing.assert_array_equal(v.U, NODES)
    np.testing.assert_array_equal(v.T, TETS)
    np.testing.assert_array_equal(mbi.read_positions(tmp_path / "m.vtk"), NODES)
    points = " ".join(str(x) for x in NODES.ravel())
    (tmp_path / "m.vtu").write_text(
        '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1">\n<UnstructuredGrid>\n'
        '<Piece NumberOfPoints="5" NumberOfCells="2">\n<Points>\n'
        f'<DataArray type="Float64" NumberOfComponents="3" format="ascii">{points}</DataArray>\n</Points>\n<Cells>\n'
        '<DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 1 2 3 4</DataArray>\n'
        '<DataArray type="Int32" Name="offsets" format="ascii">4 8</DataArray>\n'
        '<DataArray type="UInt8" Name="types" format="ascii">10 10</DataArray>\n'
        '</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n')
    u = mbi.read_control_mesh(tmp_path / "m.vtu")
    np.testing.assert_array_equal(u.U, NODES)
    np.testing.assert_array_equal(u.T, TETS)
    mbi.write_tetgen(tmp_path / "w", NODES * 3, TETS)
    w = mbi.read_control_mesh(tmp_path / "w.ele")
    np.testing.assert_array_equal(w.U, NODES * 3)
    assert w.dim == 3 and w.notes == []


def test_point_caches_and_trajectories(tmp_path):
    frames = np.random.default_rng(2).standard_normal((3, 5, 3))
    mbi.write_point_cache(tmp_path / "a.pc2", frames, start_frame=10, sample_rate=2)
    pc2 = mbi.read_point_cache(tmp_path / "a.pc2")
    np.testing.assert_array_equal(pc2.frames, frames.astype(np.float32))
    assert (pc2.start_frame, pc2.sample_rate, pc2.times) == (10, 2, [])
    mbi.write_point_cache(tmp_path / "a.mdd", frames, times=[0, 0.5, 1])
    mdd = mbi.read_point_cache(tmp_path / "a.mdd")
    np.testing.assert_array_equal(mdd.frames, frames.astype(np.float32))
    assert mdd.times == [0, 0.5, 1]
    X, times = mbi.read_trajectory(tmp_path / "a.mdd")
    np.testing.assert_array_equal(X, mdd.frames)
    assert times == [0, 0.5, 1]
    for k in range(2):
        mbi.write_vtk(tmp_path / f"t_{k}.vtk", NODES + k, TETS)
    (tmp_path / "t.pvd").write_text(
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
        '<DataSet timestep="0.5" file="t_1.vtk"/>\n<DataSet timestep="0" file="t_0.vtk"/>\n'
        '</Collection>\n</VTKFile>\n')
    entries = mbi.read_pvd(tmp_path / "t.pvd")
    assert [t for t, _ in entries] == [0, 0.5] and entries[0][1].endswith("t_0.vtk")
    X, times = mbi.read_trajectory(str(tmp_path / "t.pvd"))
    np.testing.assert_array_equal(X, [NODES, NODES + 1])
    X, _ = mbi.read_trajectory(str(tmp_path / "t_%d.vtk"))
    assert X.shape == (2, 5, 3)


def test_errors_name_the_file_or_the_argument(tmp_path):
    missing = tmp_path / "missing.obj"
    with pytest.raises(mbi.FileError, match="missing.obj"):
        mbi.read_surface(missing)
    with pytest.raises(OSError):  # also an OSError, and an mbi.Error (a ValueError)
        mbi.read_control_mesh(tmp_path / "missing.msh")
    assert issubclass(mbi.FileError, mbi.Error) and issubclass(mbi.FileError, OSError)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(mbi.FileError, match=r"bad.obj:4"):
        mbi.read_surface(bad)
    (tmp_path / "bad.node").write_text("5 3 0 0\n1 0 0\n")
    (tmp_path / "bad.ele").write_text(TET_ELE)
    with pytest.raises(mbi.FileError, match="bad.node"):
        mbi.read_control_mesh(tmp_path / "bad")
    (tmp_path / "bad.pc2").write_bytes(b"POINTCACHE2\0" + b"\1\0\0\0")
    with pytest.raises(mbi.FileError, match="bad.pc2"):
        mbi.read_point_cache(tmp_path / "bad.pc2")
    with pytest.raises(mbi.FileError, match="a point cache is .pc2 or .mdd"):
        mbi.read_point_cache(tmp_path / "x.txt")
    with pytest.raises(ValueError, match=r"V must have shape \(n, 3\)"):
        mbi.write_surface(tmp_path / "x.obj", np.zeros((4, 2)), [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"F must have shape \(t, 3\)"):
        mbi.write_surface(tmp_path / "x.obj", QUAD_V, [[0, 1, 2, 3]])
    with pytest.raises(ValueError, match=r"path must be a path"):
        mbi.read_surface(12)
    with pytest.raises(ValueError, match="encoding: unknown value"):
        mbi.write_surface(tmp_path / "x.obj", QUAD_V, [[0, 1, 2]], encoding="utf8")
    with pytest.raises(ValueError, match=r"frames must have shape"):
        mbi.write_point_cache(tmp_path / "x.pc2", np.zeros((5, 3)))
    with pytest.raises(mbi.FileError, match="x.obj"):
        mbi.write_surface(tmp_path / "x.obj", QUAD_V, [[0, 1, 7]])
    assert not (tmp_path / "x.obj").exists()
