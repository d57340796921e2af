"""Minor page faults per call of a 100-call loop (after a first call), in this fresh process:
faults.py METHOD deform|vjp|evaluate|fresh prints the mean (evaluate: mbi.evaluate of the method's Bezier
points; fresh: deform without out=, a new array each call)."""
import resource
import sys

import numpy as np

import mbi

method, call = sys.argv[1], sys.argv[2]
U, T = mbi.box_mesh(7, 7, 6)  # 1,764 tetrahedra
P = np.random.default_rng(0).uniform(0.05, 0.95, (1000 if call != "fresh" else 70_000, 3))
deformer = mbi.Deformer(U, T, P, method=method, threads=1)
X, out, dX = U * 1.01, np.empty_like(P), np.empty_like(U)
B = deformer.bezier(X)
run = {"deform": lambda: deformer.deform(X, out=out), "vjp": lambda: deformer.vjp(out, out=dX),
       "evaluate": lambda: mbi.evaluate(B, deformer.embedding, out=out, threads=1),
       "fresh": lambda: deformer.deform(X)}[call]
run()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(100):
    run()
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 100)
