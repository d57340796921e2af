"""Arrays in and out of Blender data: mesh positions, triangles, and the cage's tetrahedra.

The tetrahedra live in the cage mesh's ID property "mbi_tets" (an int array, 4 a tetrahedron),
saved in the .blend with the mesh; the control nodes are the mesh's vertices (rest positions in
float32, as Blender stores them), the boundary triangles its faces for display.
"""
import numpy as np

TETS_KEY = "mbi_tets"


def positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def triangles(mesh):
    mesh.calc_loop_triangles()
    tris = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    return tris.reshape(-1, 3)


def store_tets(mesh, T):
    mesh[TETS_KEY] = np.ascontiguousarray(T, dtype=np.int32).ravel().tolist()


def tets(mesh):
    """(m, 4) int32 tetrahedra of a cage mesh, or None when it has none."""
    if TETS_KEY not in mesh:
        return None
    flat = np.asarray(mesh[TETS_KEY].to_list(), dtype=np.int32)
    return flat.reshape(-1, 4)


def fill_cage_mesh(mesh, U, T, faces):
    """The mesh's vertices become U (all nodes, interior ones loose), its faces the boundary."""
    mesh.clear_geometry()
    mesh.from_pydata(np.asarray(U).tolist(), [], np.asarray(faces).tolist())
    store_tets(mesh, T)
    mesh.update()
