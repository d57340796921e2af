"""Interior nodes that follow the cage's boundary: the harmonic extension of the boundary's motion.

The displacement of the interior nodes minimises the Dirichlet energy of the piecewise-linear
displacement field over the rest tetrahedra (the cotangent Laplacian, i.e. P1 stiffness), the
boundary's displacement given. At rest every node stays at rest, and an affine motion of the
boundary moves the interior by the same affine map (linear precision). Pure numpy: Debian's
Blender Python has no scipy, so the operator H = -K_II^-1 K_IB is formed densely once per cage
(interior x boundary floats) and each frame is one matrix product.
"""
import numpy as np

MAX_INTERIOR = 5000  # dense K_II: 5000^2 floats = 200 MB and about a second to factor


def stiffness_blocks(U, T, interior, boundary):
    """Dense K_II (i, i) and K_IB (i, b) of the P1 stiffness of tetrahedra T over rest nodes U."""
    X = U[T]                                    # (m, 4, 3)
    D = (X[:, 1:] - X[:, :1]).transpose(0, 2, 1)  # columns x1-x0, x2-x0, x3-x0
    det = np.linalg.det(D)
    if np.any(np.abs(det) <= 1e-300):
        raise ValueError("the cage has a degenerate (flat) tetrahedron: its interior cannot follow the boundary")
    G = np.empty((len(T), 4, 3))
    G[:, 1:] = np.linalg.inv(D)                 # rows: gradients of the barycentric coordinates 1..3
    G[:, 0] = -G[:, 1:].sum(axis=1)
    local = np.einsum("mik,mjk->mij", G, G) * (np.abs(det) / 6.0)[:, None, None]
    where = np.full(len(U), -1)
    where[interior] = np.arange(len(interior))
    column = np.full(len(U), -1)
    column[boundary] = np.arange(len(boundary))
    rows = np.repeat(where[T], 4, axis=1).ravel()
    cols = np.tile(T, (1, 4)).ravel()
    values = local.reshape(len(T), 16).ravel()
    K_II = np.zeros((len(interior), len(interior)))
    K_IB = np.zeros((len(interior), len(boundary)))
    keep = (rows >= 0) & (where[cols] >= 0)
    np.add.at(K_II, (rows[keep], where[cols[keep]]), values[keep])
    keep = (rows >= 0) & (column[cols] >= 0)
    np.add.at(K_IB, (rows[keep], column[cols[keep]]), values[keep])
    return K_II, K_IB


class Extension:
    """Moves a cage's interior nodes with its boundary: X_I = U_I + H (X_B - U_B)."""

    def __init__(self, U, T, boundary_faces):
        U = np.asarray(U, dtype=np.float64)
        on_boundary = np.zeros(len(U), dtype=bool)
        on_boundary[np.asarray(boundary_faces).ravel()] = True
        self.boundary = np.flatnonzero(on_boundary)
        self.interior = np.flatnonzero(~on_boundary)
        if len(self.interior) > MAX_INTERIOR:
            raise ValueError("the cage has %d interior nodes, more than the %d the harmonic extension handles: "
                             "animate its interior nodes too (cage setting 'Interior nodes': as animated)"
                             % (len(self.interior), MAX_INTERIOR))
        self.U = U
        self.T = np.asarray(T)
        self._H = None  # formed on the first apply(): a cage whose every node moves never needs it

    @property
    def H(self):
        """The dense operator -K_II^-1 K_IB (interior x boundary)."""
        if self._H is None:
            K_II, K_IB = stiffness_blocks(self.U, self.T, self.interior, self.boundary)
            self._H = -np.linalg.solve(K_II, K_IB) if len(self.interior) else np.zeros((0, len(self.boundary)))
        return self._H

    def boundary_moved_only(self, X):
        """True when the interior nodes are exactly at rest and some boundary node is not."""
        U32 = self.U.astype(np.float32)
        X32 = np.asarray(X, dtype=np.float32)
        return (np.array_equal(X32[self.interior], U32[self.interior])
                and not np.array_equal(X32[self.boundary], U32[self.boundary]))

    def apply(self, X):
        """X (n, 3) with its interior rows replaced by the extension of its boundary rows' motion."""
        X = np.array(X, dtype=np.float64)
        X[self.interior] = self.U[self.interior] + self.H @ (X[self.boundary] - self.U[self.boundary])
        return X
