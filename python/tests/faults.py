"""Minor page faults per call of a 100-call loop (after a first call), in this fresh process:
faults.py METHOD CALL... prints the mean of each call, one a line. CALL: deform, vjp or evaluate
(mbi.evaluate of the method's Bezier points), fresh (deform without out=, a new array each call),
solve (ModifiedBI.solve), phong (Phong.M) or bezier (ModifiedBI.bezier), each with a C-order out=,
or solve_new (ModifiedBI.solve without out=: a new M each call)."""
import resource
import sys

import numpy as np

import mbi

method, names = sys.argv[1], sys.argv[2:]
U, T = mbi.box_mesh(7, 7, 6)  # 1,764 tetrahedra
P = np.random.default_rng(0).uniform(0.05, 0.95, (70_000 if "fresh" in names else 1000, 3))
deformer = mbi.Deformer(U, T, P, method=method, threads=1)
X, out, dX = U * 1.01, np.zeros_like(P), np.empty_like(U)  # out: also vjp's dL/dpositions
B = deformer.bezier(X)
solver, phong = mbi.ModifiedBI(U, T), mbi.Phong(U, T)
M, Bout = np.empty((U.size, 3)), np.empty(B.shape)
calls = {"deform": lambda: deformer.deform(X, out=out), "vjp": lambda: deformer.vjp(out, out=dX),
         "evaluate": lambda: mbi.evaluate(B, deformer.embedding, out=out, threads=1),
         "fresh": lambda: deformer.deform(X),
         "solve": lambda: solver.solve(X, out=M), "phong": lambda: phong.M(X, out=M),
         "bezier": lambda: solver.bezier(X, M, out=Bout), "solve_new": lambda: solver.solve(X)}
for name in names:
    run = calls[name]
    run()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(100):
        run()
    print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 100)
