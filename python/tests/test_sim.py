"""mbi.Simulator and mbi.FramePipeline against `mbi run`: the cantilever scene's control mesh,
material and clamp, stepped from Python, reach the control positions `mbi run` wrote (bit for
bit: both run the same C++ code) and its dense positions; and the simulator's own properties:
handles, forces, pokes, ground, energies and momenta."""
import os

import numpy as np
import pytest

import mbi
import meshes

SCENE = os.path.join(os.environ.get("MBI_SOURCE_DIR", ""), "scenes", "cantilever.toml")
# under ASan: a 20-vertex dense model, not the cylinder, and no pictures
SMALL = os.environ.get("MBI_SANITIZED") == "1"
FRAMES = 4


@pytest.fixture(scope="module")
def cantilever_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "cantilever"
    scene, mesh = SCENE, None
    if SMALL:
        scene, mesh = meshes.scene_without_pictures(SCENE, out.parent), meshes.bar_surface(str(out.parent / "bar.obj"))
    mbi.run_scene(scene, out, frames=FRAMES, gpu="off", mesh=mesh)
    return out


def cantilever(U, T):
    """The simulator of scenes/cantilever.toml: its [material], [simulation] and clamp at z = min."""
    sim = mbi.Simulator(U, T, youngs_modulus=2e5, poisson_ratio=0.3, density=500, dt=0.0333333333, substeps=2,
                        gravity=(0, -9.81, 0), mass_damping=0.5, stiffness_damping=0.01)
    sim.fix(np.flatnonzero(U[:, 2] <= U[:, 2].min()))
    return sim


def test_simulator_reaches_what_mbi_run_wrote(cantilever_run):
    U, T = mbi.read_control_mesh(cantilever_run / "control_0000.vtk")
    sim = cantilever(U, T)
    for _ in range(FRAMES):
        assert sim.step().success
    X = mbi.read_positions(cantilever_run / f"control_{FRAMES:04d}.vtk")
    assert np.abs(X - U).max() > 1e-3  # it sagged
    np.testing.assert_array_equal(sim.positions, X)
    assert sim.step_count == FRAMES and sim.time == pytest.approx(FRAMES * 0.0333333333)


def test_pipeline_reaches_the_dense_positions_of_mbi_run(cantilever_run):
    U, T = mbi.read_control_mesh(cantilever_run / "control_0000.vtk")
    dense = mbi.read_surface(cantilever_run / "mesh_0000.obj")
    pipe = mbi.FramePipeline(U, T, dense.V, cantilever(U, T), method="modified-bi", alpha=0.1)
    frames = pipe.run(FRAMES + 1)
    assert pipe.frame == FRAMES and pipe.driver == "simulation"
    cache = mbi.read_point_cache(cantilever_run / "dense.pc2").frames  # float32
    np.testing.assert_allclose(frames, cache, rtol=0, atol=1e-6)  # to float32's rounding
    last = mbi.read_surface(cantilever_run / f"mesh_{FRAMES:04d}.obj").V
    np.testing.assert_allclose(frames[-1], last, rtol=0, atol=1e-12)
    assert set(pipe.timings) == {"drive_ms", "solve_ms", "bezier_ms", "evaluate_ms", "total_ms"}


def bar():
    return mbi.box_mesh(1, 1, 4, size=(0.2, 0.2, 1.0))


def test_fixed_and_kinematic_nodes():
    U, T = bar()
    sim = mbi.Simulator(U, T, dt=0.01)
    fixed = np.flatnonzero(U[:, 2] == 0)
    moving = np.flatnonzero(U[:, 2] == 1)
    sim.fix(fixed)
    sim.add_kinematic(moving, velocity=(0.0, 0.5, 0.0))
    for _ in range(10):
        assert sim.step()
    np.testing.assert_array_equal(sim.positions[fixed], U[fixed])
    np.testing.assert_allclose(sim.positions[moving] - U[moving], np.tile([0, 0.05, 0], (len(moving), 1)), atol=1e-12)
    assert abs(sim.positions[U[:, 2] == 0.5, 1].mean()) > 1e-3  # the free middle is carried along


def test_point_force_and_poke_pull_the_material_point():
    U, T = bar()
    sim = mbi.Simulator(U, T, gravity=(0, 0, 0), dt=0.02, mass_damping=2.0)
    sim.fix(np.flatnonzero(U[:, 2] == 0))
    tip = int(np.flatnonzero(np.all(T == T[-1], axis=1))[0])
    force = sim.add_point_force(tip, [0.25] * 4, (10.0, 0, 0))
    for _ in range(20):
        sim.step()
    assert sim.positions[:, 0].max() > 0.2 + 1e-3
    sim.remove(force)
    assert not sim.has_handle(force)
    sim.reset()
    target = U[T[tip]].mean(0) + (0, 0.1, 0)
    poke = sim.add_poke(tip, [0.25] * 4, target, 1e4)
    for _ in range(60):
        sim.step()
    assert abs(sim.positions[T[tip]].mean(0)[1] - target[1]) < 0.03
    sim.set_poke_target(poke, U[T[tip]].mean(0))


def test_ground_holds_the_falling_bar():
    U, T = bar()
    sim = mbi.Simulator(U, T, dt=0.01, ground=-0.05)
    for _ in range(40):
        assert sim.step()
    assert sim.positions[:, 1].min() >= -0.05 - 1e-9


def test_energies_and_momenta_from_the_state():
    U, T = bar()
    sim = mbi.Simulator(U, T, dt=0.01)
    assert sim.elastic_energy() == pytest.approx(0, abs=1e-20)
    assert sim.rest_volume() == pytest.approx(0.04) and sim.volume() == pytest.approx(0.04)
    sim.set_velocities(np.tile([0.0, 0.0, 2.0], (sim.nodes, 1)))
    m = sim.masses
    assert m.sum() == pytest.approx(1000 * 0.04)
    assert sim.kinetic_energy() == pytest.approx(0.5 * m.sum() * 4.0)
    np.testing.assert_allclose(sim.linear_momentum(), [0, 0, 2.0 * m.sum()])
    sim.step()
    X = sim.positions
    assert sim.gravity_energy() == pytest.approx(9.81 * (m * X[:, 1]).sum())
    np.testing.assert_allclose(sim.elastic_forces().sum(0), 0, atol=1e-9)  # internal forces cancel
    sim.set_params(dt=0.005, solver="pcg")
    assert sim.dt == 0.005 and sim.solver == "pcg"


def test_solve_static_balances_gravity():
    U, T = bar()
    sim = mbi.Simulator(U, T, youngs_modulus=1e6)
    sim.fix(np.flatnonzero(U[:, 2] == 0))
    r = sim.solve_static()
    assert r.converged and sim.positions[:, 1].min() < -1e-4


def test_handle_and_given_drivers():
    U, T = bar()
    P = U.mean(0) + 0.05 * np.random.default_rng(0).standard_normal((50, 3))
    handles = np.flatnonzero(U[:, 2] == 1)
    drag = mbi.HandleDriver(U, T, handles)
    pipe = mbi.FramePipeline(U, T, P, drag)
    pipe.step()
    np.testing.assert_allclose(pipe.positions, P, atol=1e-12)  # frame 0: rest
    drag.set_targets(U[handles] + (0.1, 0, 0))
    pipe.step()
    np.testing.assert_allclose(pipe.control_positions[handles], U[handles] + (0.1, 0, 0), atol=1e-12)
    X = U + 0.01 * np.random.default_rng(1).standard_normal(U.shape)
    given = mbi.FramePipeline(U, T, P, mbi.GivenDriver(np.stack([U, X])), method="phong")
    frames = given.run(2)
    np.testing.assert_allclose(frames[1], mbi.Deformer(U, T, P, method="phong").deform(X), atol=1e-12)
    assert not given.step().ok  # past the sequence's end
    np.testing.assert_allclose(given.evaluate_with("bi"), mbi.Deformer(U, T, P, method="bi").deform(X), atol=1e-12)


def test_refused_input_names_the_argument():
    U, T = bar()
    with pytest.raises(ValueError, match=r"U must have shape \(n, 3\)"):
        mbi.Simulator(U[:, :2], T[:, :3])
    with pytest.raises(ValueError, match="unknown simulation parameter \"dtt\""):
        mbi.Simulator(U, T, dtt=0.1)
    with pytest.raises(ValueError, match="gravity must have shape"):
        mbi.Simulator(U, T, gravity=(0, 1))
    with pytest.raises(ValueError, match="poisson_ratio must lie in"):
        mbi.Simulator(U, T, poisson_ratio=0.7)
    sim = mbi.Simulator(U, T)
    with pytest.raises(ValueError, match=r"X must have shape \(20, 3\)"):
        sim.set_positions(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="nodes"):
        sim.fix([[0, 1]])
    with pytest.raises(ValueError, match="driver must be"):
        mbi.FramePipeline(U, T, U, driver="sim")
    with pytest.raises(ValueError, match="integrator: unknown value"):
        sim.set_params(integrator="euler")


def test_per_element_materials_rotation_and_midpoint():
    U, T = bar()
    one = mbi.Simulator(U, T, youngs_modulus=3e5, poisson_ratio=0.35, density=800, dt=0.01)
    each = mbi.Simulator(U, T, element_materials=np.tile([3e5, 0.35, 800], (len(T), 1)), dt=0.01)
    for s in (one, each):
        s.fix(np.flatnonzero(U[:, 2] == 0))
        s.step()
    np.testing.assert_array_equal(one.positions, each.positions)
    spin = mbi.Simulator(U, T, dt=0.01)
    top = np.flatnonzero(U[:, 2] == 1)
    spin.add_kinematic(top, center=(0.1, 0.1, 0), axis=(0, 0, 1), angular_velocity=2 * np.pi)
    for _ in range(50):  # half a turn in 0.5 s
        spin.step()
    np.testing.assert_allclose(spin.positions[top, :2], 0.2 - U[top, :2], atol=1e-9)
    free = mbi.Simulator(U, T, dt=0.01, gravity=(0, 0, 0), integrator="implicit-midpoint", newton_iterations=4,
                         newton_tolerance=1e-12)
    free.set_velocities(np.random.default_rng(3).standard_normal(U.shape) * 0.1)
    p0 = free.linear_momentum()
    for _ in range(5):
        assert free.step()
    np.testing.assert_allclose(free.linear_momentum(), p0, atol=1e-9)


def test_pipeline_normals_methods_and_reset():
    U, T = bar()
    P = U.mean(0) + 0.05 * np.random.default_rng(0).standard_normal((40, 3))
    N = np.tile([0.0, 0.0, 1.0], (len(P), 1))
    X = U + 0.02 * np.random.default_rng(4).standard_normal(U.shape)
    pipe = mbi.FramePipeline(U, T, P, mbi.GivenDriver(X), rest_normals=N, alpha=0.2)
    pipe.step()
    positions, normals = mbi.Deformer(U, T, P, rest_normals=N, alpha=0.2).deform(X, normals=True)
    np.testing.assert_allclose(pipe.positions, positions, atol=1e-12)
    np.testing.assert_allclose(pipe.normals, normals, atol=1e-12)
    pipe.set_method("bi")
    pipe.step()
    assert pipe.method == "bi" and pipe.frame == 1
    np.testing.assert_allclose(pipe.positions, mbi.Deformer(U, T, P, method="bi").deform(X), atol=1e-12)
    np.testing.assert_array_equal(pipe.M, 0)
    pipe.reset()
    assert pipe.frame == -1
    soft = mbi.FramePipeline(U, T, P, mbi.HandleDriver(U, T, np.flatnonzero(U[:, 2] == 0), mode="soft"))
    assert soft.step() and soft.driver == "handles"
