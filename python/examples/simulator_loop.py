"""A numpy-only simulator drives mbi: a coarse tetrahedral bar (a mass-spring system along the
tetrahedra's edges, fixed at one end, sagging under gravity) moves a dense set of points embedded
in it, every frame, through one mbi.Deformer (embedding and precompute once, then one call a
frame into the same out= array: the loop allocates no dense array).

    PYTHONPATH=build/release/python python3 python/examples/simulator_loop.py [--points N] [--frames F]
"""
import argparse
import itertools
import time

import numpy as np
import numpy.typing as npt

import mbi


class MassSpring:
    """Springs along the edges of the tetrahedra, lumped masses, symplectic Euler with damping.
    Units: m, kg, s, N/m."""

    def __init__(self, U: npt.NDArray[np.float64], T: npt.NDArray[np.int32], stiffness: float = 1000.0,
                 mass: float = 0.02, damping: float = 2.0, gravity: float = -9.81) -> None:
        pairs = {tuple(sorted((t[a], t[b]))) for t in T for a, b in itertools.combinations(range(4), 2)}
        self.edges = np.array(sorted(pairs))
        self.rest = np.linalg.norm(U[self.edges[:, 1]] - U[self.edges[:, 0]], axis=1)
        self.x, self.v = U.copy(), np.zeros_like(U)
        self.fixed = U[:, 0] < 1e-9  # the end at x = 0 is clamped
        self.k, self.m, self.c, self.g = stiffness, mass, damping, gravity

    def step(self, dt: float) -> npt.NDArray[np.float64]:
        d = self.x[self.edges[:, 1]] - self.x[self.edges[:, 0]]
        length = np.linalg.norm(d, axis=1)
        f_edge = (self.k * (length - self.rest) / length)[:, None] * d
        f = np.zeros_like(self.x)
        np.add.at(f, self.edges[:, 0], f_edge)
        np.add.at(f, self.edges[:, 1], -f_edge)
        f[:, 2] += self.m * self.g
        f -= self.c * self.m * self.v
        self.v += dt * f / self.m
        self.v[self.fixed] = 0
        self.x += dt * self.v
        return self.x


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--points", type=int, default=200_000, help="dense points (default 200000)")
    parser.add_argument("--frames", type=int, default=60, help="frames (default 60)")
    parser.add_argument("--method", default="modified-bi", choices=mbi.METHODS)
    args = parser.parse_args()

    U, T = mbi.box_mesh(6, 2, 2, (3.0, 1.0, 1.0))
    rng = np.random.default_rng(0)
    P = rng.uniform([0.05, 0.05, 0.05], [2.95, 0.95, 0.95], size=(args.points, 3))  # the dense model
    t0 = time.perf_counter()
    deformer = mbi.Deformer(U, T, P, method=args.method)
    print(f"bound {args.points} points to {len(U)} control vertices ({len(T)} tetrahedra), "
          f"{args.method}, in {1e3 * (time.perf_counter() - t0):.1f} ms")

    sim = MassSpring(U, T)
    positions = np.empty_like(P)  # written in place every frame
    deform_s = 0.0
    for _ in range(args.frames):
        for _ in range(20):  # substeps: explicit integration needs a small step
            X = sim.step(1.0 / 1200)
        t0 = time.perf_counter()
        deformer.deform(X, out=positions)
        deform_s += time.perf_counter() - t0

    tip = P[:, 0] > 2.8
    sag = P[tip, 2].mean() - positions[tip, 2].mean()
    control_sag = U[U[:, 0] > 2.9, 2].mean() - X[U[:, 0] > 2.9, 2].mean()
    print(f"{args.frames} frames, {1e3 * deform_s / args.frames:.2f} ms a frame in mbi")
    print(f"tip sag: dense points {sag:.4f} m, control vertices {control_sag:.4f} m")
    assert np.isfinite(positions).all()
    assert sag > 0.01 and abs(sag - control_sag) < 0.25 * control_sag, "the dense points follow the bar"
    print("ok: the dense model follows the simulated bar")


if __name__ == "__main__":
    main()
