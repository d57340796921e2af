"""Interior nodes that follow the cage's boundary: the harmonic extension of the boundary's motion.

The displacement of the interior nodes minimises the Dirichlet energy of the piecewise-linear
displacement field over the rest tetrahedra (P1 stiffness), the boundary's displacement given:
mbi.HarmonicExtension, one sparse factor per cage and one solve a frame. At rest every node stays
at rest, and an affine motion of the boundary moves the interior by the same affine map.
"""
import numpy as np

from . import module


class Extension:
    """Moves a cage's interior nodes with its boundary."""

    def __init__(self, U, T):
        self.U = np.asarray(U, dtype=np.float64)
        self.U32 = self.U.astype(np.float32)  # as Blender stores positions: compared every frame
        self.extension = module.load().HarmonicExtension(self.U, T)  # fixed: the boundary's nodes
        self.boundary = self.extension.fixed_nodes
        self.interior = self.extension.free_nodes

    def boundary_moved_only(self, X):
        """True when the interior nodes are exactly at rest and some boundary node is not."""
        X32 = np.asarray(X, dtype=np.float32)
        return (np.array_equal(X32[self.interior], self.U32[self.interior])
                and not np.array_equal(X32[self.boundary], self.U32[self.boundary]))

    def apply(self, X):
        """X (n, 3) with its interior rows replaced by the extension of its boundary rows' motion."""
        return self.extension.apply(np.asarray(X, dtype=np.float64))
