"""Small test meshes and poses in numpy, and a reference implementation of the
method's defining formula to check the package against."""
import itertools
import os

import numpy as np

import mbi


def box(nx, ny, nz, size=(1.0, 1.0, 1.0)):
    """A box of nx*ny*nz cells, 6 positively oriented tetrahedra a cell (mbi.box_mesh)."""
    return mbi.box_mesh(nx, ny, nz, size)


def square(nx, ny, size=(1.0, 1.0)):
    """A rectangle of nx*ny squares, 2 positively oriented triangles a square."""
    def idx(i, j):
        return j * (nx + 1) + i
    U = np.array([[size[0] * i / nx, size[1] * j / ny] for j in range(ny + 1) for i in range(nx + 1)])
    T = []
    for j, i in itertools.product(range(ny), range(nx)):
        T.append([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)])
        T.append([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)])
    return U, np.array(T, dtype=np.int64)


def jittered(d, seed=1):
    """A jittered control mesh: 4x2x2 cells of [0,2]x[0,1]x[0,1] (3D) or 5x3 of the unit square."""
    U, T = box(4, 2, 2, (2.0, 1.0, 1.0)) if d == 3 else square(5, 3)
    rng = np.random.default_rng(seed)
    lo, hi = U.min(0), U.max(0)
    interior = np.all((U > lo + 1e-12) & (U < hi - 1e-12), axis=1)
    U = U.copy()
    U[interior] += rng.uniform(-0.06, 0.06, size=(interior.sum(), d))
    return U, T


def points(U, p, seed=2, margin=0.02):
    """p random points in U's bounding box, a few of them slightly outside it."""
    rng = np.random.default_rng(seed)
    lo, hi = U.min(0), U.max(0)
    return lo + rng.uniform(-margin, 1 + margin, size=(p, U.shape[1])) * (hi - lo)


def pose(U, seed=3, amount=0.3):
    """A smooth bend plus a little noise."""
    rng = np.random.default_rng(seed)
    X = U + 0.03 * rng.standard_normal(U.shape)
    X[:, 1] += amount * U[:, 0] ** 2
    X[:, 0] += amount * np.sin(U[:, -1])
    return X


def reference(U, T, X, M, emb):
    """x(u) = sum_i phi_i(u) (x_i + M_i (u - u_i)) at every embedded point (docs/method.md)."""
    d = U.shape[1]
    e = emb.element
    b = emb.bary
    u = np.einsum("pk,pkc->pc", b, U[T[e]])
    x = np.zeros((len(e), d))
    for k in range(d + 1):
        i = T[e, k]
        Mi = M.reshape(-1, d, d)[i]
        x += b[:, k, None] * (X[i] + np.einsum("prc,pc->pr", Mi, u - U[i]))
    return x


def bar_surface(path):
    """Writes the surface of a 1 x 1 x 4 box centred on the z axis (the extent of the scenes'
    built-in cylinder) to `path`: a small dense model for runs under the sanitizers."""
    U, T = mbi.box_mesh(1, 1, 4, size=(1.0, 1.0, 4.0))
    U = U - (0.5, 0.5, 0.0)
    mbi.write_surface(path, U, mbi.boundary_faces(U, T))
    return path


def scene_without_pictures(scene, folder):
    """A copy of a scene file of scenes/ (built-in models only) in `folder` that writes no
    pictures: the software renderer is the slow part of a short run under the sanitizers."""
    with open(scene) as f:
        text = f.read()
    assert "[output]\n" in text, scene
    path = os.path.join(str(folder), os.path.basename(scene))
    with open(path, "w") as f:
        f.write(text.replace("[output]\n", "[output]\nimage = false\n"))
    return path
