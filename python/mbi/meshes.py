"""Control meshes to start from, in numpy (no compiled code)."""
import itertools
from typing import List, Sequence, Tuple

import numpy as np
import numpy.typing as npt


def box_mesh(nx: int, ny: int, nz: int, size: Sequence[float] = (1.0, 1.0, 1.0)
             ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """A box of nx * ny * nz cells from the origin to `size` (units of your model), 6 positively
    oriented tetrahedra a cell (Kuhn split): U (n, 3) float64, T (6 nx ny nz, 4) int32."""
    if min(nx, ny, nz) < 1:
        raise ValueError(f"box_mesh needs at least one cell along each axis, got {nx} x {ny} x {nz}")

    def idx(i: int, j: int, k: int) -> int:
        return (k * (ny + 1) + j) * (nx + 1) + i

    U = np.array([[size[0] * i / nx, size[1] * j / ny, size[2] * k / nz]
                  for k in range(nz + 1) for j in range(ny + 1) for i in range(nx + 1)])
    T: List[List[int]] = []
    for k, j, i in itertools.product(range(nz), range(ny), range(nx)):
        for perm in itertools.permutations(range(3)):
            c, v = [i, j, k], [idx(i, j, k)]
            for s in range(3):
                c[perm[s]] += 1
                v.append(idx(*c))
            if np.linalg.det(U[v[1:]] - U[v[0]]) < 0:
                v[2], v[3] = v[3], v[2]
            T.append(v)
    return U, np.array(T, dtype=np.int32)
