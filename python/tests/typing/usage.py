"""Every public name of mbi, called as a user would, with the types a reader expects written out:
`mypy --strict` checks it against the stubs (test_types.py), and the test runs it, so that the
calls are real. Argument: a scratch folder; MBI_SOURCE_DIR: the repository (for a scene)."""
import os
import sys
import warnings
from typing import Any, Dict, List, Tuple

import numpy as np
import numpy.typing as npt
import torch

import mbi
import mbi.torch

F64 = npt.NDArray[np.float64]
F32 = npt.NDArray[np.float32]
I32 = npt.NDArray[np.int32]


def core(tmp: str) -> None:
    up = np.tile([0.0, 0.0, 1.0], (40, 1))
    U, T = mbi.box_mesh(2, 2, 2, size=(1.0, 1.0, 2.0))
    tets: I32 = T
    P: F64 = np.random.default_rng(0).uniform(0.1, 0.9, (40, 3)) * (1.0, 1.0, 2.0)
    for method in mbi.METHODS:  # Literal-typed: Deformer takes them as they are
        deformer = mbi.Deformer(U, tets, P, method=method, rest_normals=up)
        positions: F64 = deformer.deform(U)
        fast: F32 = deformer.deform(U, dtype=np.float32)
        out = np.empty((40, 3))
        same: F64 = deformer.deform(U, out=out)
        batch: F64 = deformer.deform(np.stack([U, U]))
        pos, nrm = deformer.deform(U, normals_out=np.empty((40, 3)))
        grad: F64 = deformer.vjp(np.ones_like(positions))
        into: F64 = deformer.vjp(np.ones_like(positions), out=np.empty_like(U))
        assert same is out and batch.shape == (2, 40, 3) and fast.dtype == np.float32 and pos.shape == nrm.shape
        assert grad.shape == into.shape == U.shape and deformer.M(U).shape == (27 * 3, 3)
        assert deformer.bezier(U).shape[1] == 3 and deformer.method == method
    with warnings.catch_warnings(record=True) as caught:  # points outside the control mesh: a warning, counts
        warnings.simplefilter("always")
        outside = mbi.Deformer(U, T, P + (0.0, 0.0, 3.0), max_outside=2.0)
    far: int = outside.outside_points
    distance: float = outside.max_outside_distance
    assert far > 0 and distance > 0 and issubclass(caught[0].category, mbi.OutsideWarning)
    embedding: mbi.Embedding = mbi.embed(U, T, P)
    element: I32 = embedding.element
    assert element.dtype == np.int32 and mbi.embedded_positions(U, T, embedding).shape == P.shape
    solver = mbi.ModifiedBI(U, T, alpha=mbi.default_alpha(3), solve_path="automatic", factorization="automatic",
                            max_memory="8G")
    estimate: mbi.MemoryEstimate = mbi.estimate_memory(U, T, len(P))
    limit: Tuple[float, str] = mbi.memory_limit()
    assert estimate.peak_bytes > estimate.factor_bytes and limit[0] > 0
    M: F64 = solver.solve(U)
    B: F64 = solver.bezier(U, M)
    assert solver.solve_transpose(M).shape == U.shape
    phong = mbi.Phong(U, T)
    assert phong.M(U).shape == M.shape and phong.M_transpose(M).shape == U.shape
    exact: F64 = mbi.evaluate(B, embedding)
    both: Tuple[F64, F64] = mbi.evaluate(B, embedding, rest_normals=up)
    kernel = mbi.FastEvaluator(embedding, simd="auto")
    approx: F32 = kernel.evaluate(B)
    assert np.abs(approx - exact).max() < 1e-5 and both[0].shape == exact.shape
    assert mbi.FastEvaluator.supported("portable")
    assert mbi.bezier_bi(U, T).shape == mbi.bezier_points(U, T, U, np.zeros_like(M)).shape
    dX, dM = mbi.bezier_transpose(U, T, mbi.evaluate_transpose(embedding, np.ones_like(P), len(T)))
    assert dX.shape == U.shape and dM.shape == M.shape
    table: mbi.DiscontinuityTable = mbi.discontinuity_table(solver, U, M)
    summary: mbi.Summary = table.bi
    assert summary.max >= 0 and mbi.face_discontinuity(U, T, U, M).shape[0] == len(mbi.interior_faces(T))
    faces: I32 = mbi.boundary_faces(U, T)
    assert faces.shape[1] == 3
    interior = mbi.HarmonicExtension(U, T)
    moved: F64 = interior.apply(U)
    nodes: I32 = interior.free_nodes
    assert moved.shape == U.shape and len(nodes) + len(interior.fixed_nodes) == len(U) and interior.memory_bytes >= 0
    mbi.validate_mesh(U, T)
    mbi.set_threads(0)
    assert mbi.threads() >= 1 and isinstance(mbi.threads_available(), bool)
    assert isinstance(mbi.cholmod_available(), bool)
    X = torch.tensor(U, requires_grad=True)
    model = mbi.torch.Deform(mbi.Deformer(U, T, P))
    loss = (model(X) ** 2).sum()
    loss.backward()
    from_numpy: torch.Tensor = mbi.torch.deform(model.deformer, U)
    assert X.grad is not None and from_numpy.shape == (40, 3)
    assert mbi.torch.DeformFunction is not None and mbi.torch.VjpFunction is not None
    (g,) = torch.autograd.grad((mbi.torch.deform(model.deformer, X) ** 2).sum(), X, create_graph=True)
    (hv,) = torch.autograd.grad(g, X, grad_outputs=torch.ones_like(X))  # a Hessian-vector product
    assert hv.shape == X.shape


def simulation(tmp: str) -> None:
    U, T = mbi.box_mesh(1, 1, 2)
    for integrator in mbi.INTEGRATORS:
        for solver in mbi.SOLVERS:
            sim = mbi.Simulator(U, T, youngs_modulus=1e5, integrator=integrator, solver=solver, dt=0.01)
            fixed: int = sim.fix(U[:, 2] == 0)  # a boolean mask of the nodes
            step: mbi.StepResult = sim.step()
            assert step.success and sim.has_handle(fixed)
    static: mbi.StaticResult = sim.solve_static(max_iterations=5)
    assert static.iterations >= 0
    P = U * 0.5 + 0.25
    pipe = mbi.FramePipeline(U, T, P, sim, method="phong")
    frame: mbi.FrameResult = pipe.step()
    assert frame.ok and pipe.run(2).shape == (2, len(P), 3)
    given = mbi.GivenDriver(np.stack([U, U * 1.1]))
    assert mbi.FramePipeline(U, T, P, given).run(2).shape == (2, len(P), 3)
    handles = mbi.HandleDriver(U, T, [0, 1], mode="soft")
    handles.set_targets(U[:2] + 0.1)
    assert mbi.FramePipeline(U, T, P, handles).run(2).shape[0] == 2
    floor = mbi.Collider.plane((0, 0, -0.1), (0, 0, 1), friction=0.5).moving(velocity=(0, 0, 0.1))
    free = mbi.Simulator(U, T, youngs_modulus=1e5, dt=0.01, newton_iterations=5)
    touching = mbi.FramePipeline.with_contact(U, T, P, free, [floor, mbi.Collider.sphere((0, 0, 3), 0.2)], method="bi")
    assert touching.run(2).shape[0] == 2 and touching.contact is not None
    depth, normal = floor.distance((0, 0, 0), time=2.0)
    assert depth < 0 and normal.shape == (3,)
    assert mbi.batch.material_grid([1e5], [0.3])[0]["youngs_modulus"] == 1e5
    assert mbi.batch.run_batch(mbi.batch.simulate_material, mbi.batch.material_grid([2e5], [0.3]), frames=1,
                               cells=(1, 1, 2), points=10)[0]["tip_sag"] >= 0


def files(tmp: str) -> None:
    U, T = mbi.box_mesh(1, 1, 1)
    surface = mbi.Surface(U, T[:, :3])
    obj = os.path.join(tmp, "s.obj")
    mbi.write_surface(obj, surface)
    V, F = mbi.read_surface(obj)
    assert V.shape == (8, 3) and F.dtype == np.int32
    tri = os.path.join(tmp, "t.obj")
    mbi.write_surface(tri, [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], encoding="ascii")  # integer positions
    points = os.path.join(tmp, "p.xyz")
    mbi.write_points(points, U)
    assert mbi.read_points(points).shape == U.shape
    base = os.path.join(tmp, "c")
    mbi.write_tetgen(base, U, T)
    control: mbi.ControlMesh = mbi.read_control_mesh(base + ".node")
    U2, T2 = control
    assert U2.shape == U.shape and mbi.read_positions(base + ".node").shape == U.shape
    vtk = os.path.join(tmp, "c.vtk")
    mbi.write_vtk(vtk, U, T, point_vectors=U)
    pc2 = os.path.join(tmp, "c.pc2")
    mbi.write_point_cache(pc2, np.stack([U, U]))
    cache: mbi.PointCache = mbi.read_point_cache(pc2)
    frames, times = mbi.read_trajectory(pc2)
    assert cache.frames.shape == frames.shape == (2, 8, 3) and times == []
    pvd = os.path.join(tmp, "c.pvd")
    with open(pvd, "w") as f:
        f.write('<VTKFile type="Collection"><Collection><DataSet timestep="0" file="c.vtk"/></Collection></VTKFile>')
    entries: List[Tuple[float, str]] = mbi.read_pvd(pvd)
    assert len(entries) == 1
    try:
        mbi.read_surface(os.path.join(tmp, "missing.obj"))
    except mbi.FileError as e:
        error: mbi.Error = e
        assert "missing.obj" in str(error)
    cage = mbi.cage(U * 10, vertices=30, mesher="voxel")
    CU, CT = cage
    assert isinstance(cage, mbi.Cage) and CT.dtype == np.int32 and CU.shape[1] == 3
    scene = os.path.join(os.environ["MBI_SOURCE_DIR"], "scenes", "cantilever.toml")
    model = mbi.batch.deform_model(obj, tmp, vertices=20, frames=1)
    assert model["digest"] == mbi.batch.digest(mbi.read_surface(model["obj"]).V)
    run: Dict[str, Any] = mbi.run_scene(scene, os.path.join(tmp, "run"), frames=1, gpu="off", method="bi")
    assert run["frames"] >= 1


if __name__ == "__main__":
    core(sys.argv[1])
    simulation(sys.argv[1])
    files(sys.argv[1])
    print("ok: every public name was called")
