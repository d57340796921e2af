"""Control meshes to start from, in numpy (no compiled code)."""
import itertools

import numpy as np


def box_mesh(nx, ny, nz, size=(1.0, 1.0, 1.0)):
    """A box of nx * ny * nz cells from the origin to `size` (units of your model), 6 positively
    oriented tetrahedra a cell (Kuhn split): U (n, 3) float64, T (6 nx ny nz, 4) int64."""
    if min(nx, ny, nz) < 1:
        raise ValueError(f"box_mesh needs at least one cell along each axis, got {nx} x {ny} x {nz}")

    def idx(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i

    U = np.array([[size[0] * i / nx, size[1] * j / ny, size[2] * k / nz]
                  for k in range(nz + 1) for j in range(ny + 1) for i in range(nx + 1)])
    T = []
    for k, j, i in itertools.product(range(nz), range(ny), range(nx)):
        for perm in itertools.permutations(range(3)):
            c, v = [i, j, k], [idx(i, j, k)]
            for s in range(3):
                c[perm[s]] += 1
                v.append(idx(*c))
            if np.linalg.det(U[v[1:]] - U[v[0]]) < 0:
                v[2], v[3] = v[3], v[2]
            T.append(v)
    return U, np.array(T, dtype=np.int64)
