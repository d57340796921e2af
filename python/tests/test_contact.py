"""Contact at the dense points on the pipeline's coupled step: FramePipeline.from_scene steps a
scene with contact = "surface" exactly as `mbi run` writes it; FramePipeline.with_contact, built
from arrays, a Python Simulator and mbi.Collider, steps the same scene alike; the figures of each
frame (contact points, Newton iterations) are metrics.json's; colliders are checked."""
import math
import os

import numpy as np
import pytest

import mbi

DT = 1.0 / 30.0
GROUND = -0.05
STIFFNESS = 2e6
TOLERANCE = 1e-4


def sphere_surface(n_lat=12, n_lon=24, radius=0.4, center=(0.5, 0.5, 0.5)):
    """A latitude-longitude sphere: V (p, 3), F (f, 3)."""
    V = [(0.0, -radius, 0.0)]
    for i in range(1, n_lat):
        theta = math.pi * i / n_lat
        for j in range(n_lon):
            phi = 2 * math.pi * j / n_lon
            V.append((radius * math.sin(theta) * math.cos(phi), -radius * math.cos(theta),
                      radius * math.sin(theta) * math.sin(phi)))
    V.append((0.0, radius, 0.0))
    ring = lambda i, j: 1 + (i - 1) * n_lon + j % n_lon  # noqa: E731
    F = [(0, ring(1, j + 1), ring(1, j)) for j in range(n_lon)]
    for i in range(1, n_lat - 1):
        for j in range(n_lon):
            F += [(ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)), (ring(i, j), ring(i + 1, j + 1), ring(i + 1, j))]
    top = len(V) - 1
    F += [(top, ring(n_lat - 1, j), ring(n_lat - 1, j + 1)) for j in range(n_lon)]
    return np.array(V) + np.array(center), np.array(F, dtype=np.int32)


@pytest.fixture
def scene(tmp_path):
    """A ball in a 3 x 3 x 3 box cage (0.1 m under it: the cage's margin) dropped onto a ground."""
    U, T = mbi.box_mesh(3, 3, 3)
    V, F = sphere_surface()
    mbi.write_tetgen(str(tmp_path / "cage"), U, T)
    mbi.write_surface(str(tmp_path / "ball.obj"), V, F)
    text = f"""
[dense]
path = "ball.obj"
[control]
path = "cage"
[material]
young = 2e5
density = 500
[simulation]
dt = {DT!r}
frames = 24
gravity = [0, -9.81, 0]
damping_mass = 1.0
ground = {GROUND!r}
contact = "surface"
contact_stiffness = {STIFFNESS!r}
newton_tolerance = {TOLERANCE!r}
[interpolation]
method = "modified-bi"
gpu = "off"
[output]
image = false
mesh_format = "none"
control_vtk = false
"""
    (tmp_path / "ball.toml").write_text(text)
    cage = mbi.read_control_mesh(str(tmp_path / "cage.node"))  # as the scene reads them
    return {"path": tmp_path / "ball.toml", "U": cage.U, "T": cage.T, "V": mbi.read_surface(str(tmp_path / "ball.obj")).V,
            "out": tmp_path / "out"}


def run_frames(pipe, frames):
    positions, figures = [], []
    for _ in range(frames + 1):
        assert pipe.step()
        positions.append(pipe.positions)
        figures.append(pipe.contact)
    return np.array(positions), figures


def run_and_step(scene):
    """mbi run of the scene, and FramePipeline.from_scene stepped as many frames: (run, positions,
    figures, size), the positions checked against the run's point cache."""
    run = mbi.run_scene(scene["path"], scene["out"])
    assert not run["failed"]
    written = np.asarray(mbi.read_point_cache(os.path.join(run["out_dir"], "dense.pc2")).frames)
    positions, figures = run_frames(mbi.FramePipeline.from_scene(scene["path"]), 24)
    size = np.linalg.norm(np.ptp(scene["V"], axis=0))
    assert np.abs(positions - written).max() <= 1e-6 * size  # the point cache holds float32
    return run, positions, figures, size


def test_from_scene_steps_as_mbi_run_writes(scene):
    run, positions, figures, size = run_and_step(scene)
    frames = run["metrics"]["frames"]
    assert [f["touching"] for f in figures] == [f["contact_points"] for f in frames]
    assert [f["newton_iterations"] for f in figures] == [f["newton_iterations"] for f in frames]
    # it fell onto the ground and rests there on its dense surface, not on the cage's margin
    assert figures[-1]["touching"] > 0
    assert abs(positions[-1][:, 1].min() - GROUND) <= 1e-3 * size


def test_with_contact_from_arrays_steps_as_the_scene(scene):
    sim = mbi.Simulator(scene["U"], scene["T"], youngs_modulus=2e5, poisson_ratio=0.45, density=500.0, dt=DT,
                        gravity=(0, -9.81, 0), mass_damping=1.0, newton_iterations=20, newton_tolerance=TOLERANCE)
    ground = mbi.Collider.plane((0, GROUND, 0), (0, 1, 0))
    pipe = mbi.FramePipeline.with_contact(scene["U"], scene["T"], scene["V"], sim, [ground], stiffness=STIFFNESS)
    positions, figures = run_frames(pipe, 24)
    expected, expected_figures = run_frames(mbi.FramePipeline.from_scene(scene["path"]), 24)
    assert np.array_equal(positions, expected)
    assert figures == expected_figures
    assert pipe.driver == "simulation"


def test_without_contact_the_cage_margin_stays(scene):
    """The negative control: the simulator's ground plane on the control nodes (contact = control)
    leaves the cage's 0.1 m margin under the ball."""
    sim = mbi.Simulator(scene["U"], scene["T"], youngs_modulus=2e5, poisson_ratio=0.45, density=500.0, dt=DT,
                        gravity=(0, -9.81, 0), mass_damping=1.0, ground=GROUND)
    pipe = mbi.FramePipeline(scene["U"], scene["T"], scene["V"], sim)
    positions, figures = run_frames(pipe, 24)
    assert figures[-1] is None
    assert positions[-1][:, 1].min() - GROUND > 0.05


def test_contact_on_a_subset_and_a_moving_sphere(scene):
    sim = mbi.Simulator(scene["U"], scene["T"], youngs_modulus=2e5, density=500.0, dt=DT, gravity=(0, 0, 0),
                        newton_iterations=20)
    V = scene["V"]
    top = np.flatnonzero(V[:, 1] > 0.7)
    ball = mbi.Collider.sphere((0.5, 1.3, 0.5), 0.25).moving(velocity=(0, -1.0, 0), stop=0.2)
    pipe = mbi.FramePipeline.with_contact(scene["U"], scene["T"], V, sim, [ball], points=top, method="bi")
    positions, figures = run_frames(pipe, 8)
    assert max(f["touching"] for f in figures) > 0
    # the sphere pressed the top down; nothing else touches
    assert positions[-1][top, 1].max() < V[top, 1].max() - 0.01


def test_colliders_are_checked():
    with pytest.raises(mbi.Error, match="radius"):
        mbi.Collider.sphere((0, 0, 0), -1.0)
    with pytest.raises(mbi.Error, match="friction"):
        mbi.Collider.plane((0, 0, 0), (0, 1, 0), friction=float("nan"))
    with pytest.raises(mbi.Error, match="normal"):
        mbi.Collider.plane((0, 0, 0), (0, 0, 0))
    with pytest.raises(mbi.Error, match="axes"):
        mbi.Collider.box((0, 0, 0), (1, 1, 1), [[1, 0, 0], [1, 0, 0], [0, 0, 1]])
    with pytest.raises(mbi.Error, match="stop"):
        mbi.Collider.sphere((0, 0, 0), 1.0).moving(start=2.0, stop=1.0)
    box = mbi.Collider.box((0, 0, 0), (1, 1, 1), [[0, 1, 0], [-1, 0, 0], [0, 0, 1]], friction=0.5)
    value, normal = box.distance((2, 0, 0))
    assert (box.shape, box.friction, value) == ("box", 0.5, 1.0)
    assert np.allclose(normal, (1, 0, 0))



def box_mesh(half):
    V = np.array([[(1 if i & 1 else -1) * half[0], (1 if i & 2 else -1) * half[1], (1 if i & 4 else -1) * half[2]]
                  for i in range(8)])
    F = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7],
                  [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
    return V, F


def test_a_mesh_collider_measures_as_the_analytic_shape_within_a_voxel(scene):
    half = (0.6, 0.3, 0.4)
    V, F = box_mesh(half)
    voxel = 0.02
    mesh = mbi.Collider.mesh(V, F.astype(np.int32), voxel_size=voxel, friction=0.2).moving(velocity=(0, 0, 1))
    box = mbi.Collider.box((0, 0, 0), half).moving(velocity=(0, 0, 1))
    assert (mesh.shape, mesh.friction) == ("mesh", 0.2)
    P = np.random.default_rng(4).uniform(-0.7, 0.7, (2000, 3))
    d_mesh, _ = mesh.distances(P, time=0.1)
    d_box, _ = box.distances(P, time=0.1)
    near = d_box < 3 * voxel  # the band outside, all of the inside
    assert near.sum() > 500
    assert np.abs(d_mesh[near] - d_box[near]).max() < voxel
    with pytest.raises(mbi.Error, match="closed"):
        mbi.Collider.mesh(V, F[:-1])
    with pytest.raises(mbi.Error, match="F"):
        mbi.Collider.mesh(V, F[:, :2])


def test_contact_with_a_mesh_collider_presses_like_the_box(scene):
    """A box mesh pushed down onto the top of the cage's model dents it as the analytic box does."""
    V = scene["V"]
    top = np.flatnonzero(V[:, 1] > 0.7)
    bv, bf = box_mesh((0.2, 0.1, 0.2))
    shapes = {"mesh": mbi.Collider.mesh(bv + (0.5, 1.15, 0.5), bf, voxel_size=0.01),
              "box": mbi.Collider.box((0.5, 1.15, 0.5), (0.2, 0.1, 0.2))}
    lowest = {}
    for name, c in shapes.items():
        sim = mbi.Simulator(scene["U"], scene["T"], youngs_modulus=2e5, density=500.0, dt=DT, gravity=(0, 0, 0),
                            newton_iterations=20)
        pipe = mbi.FramePipeline.with_contact(scene["U"], scene["T"], V, sim, [c.moving(velocity=(0, -1.0, 0),
                                              stop=0.2)], points=top, method="bi")
        positions, figures = run_frames(pipe, 8)
        assert max(f["touching"] for f in figures) > 0
        lowest[name] = positions[-1][top, 1].min()
    assert lowest["box"] < V[top, 1].max() - 0.01
    assert abs(lowest["mesh"] - lowest["box"]) < 0.01 + 0.02  # a voxel of the level set and the penalty's give


def test_distances_at_many_points_are_distance_at_each():
    rng = np.random.default_rng(3)
    P = rng.uniform(-2, 2, (40, 3))
    shapes = [mbi.Collider.plane((0, 0.1, 0), (0.2, 1, 0)), mbi.Collider.sphere((0.3, 0, 0), 0.8),
              mbi.Collider.box((0, 0, 0), (1, 0.5, 0.7), [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]),
              mbi.Collider.capsule((-1, 0, 0), (1, 0.5, 0), 0.4).moving(velocity=(0, 0, 1), twist_rate=2.0)]
    # a Fortran-order copy, every other row of a larger array, a broadcast row
    layouts = [P, np.asfortranarray(P), np.repeat(P, 2, axis=0)[::2], np.broadcast_to(P[3], (5, 3))]
    for c in shapes:
        for Q in layouts:
            d, n = c.distances(Q, time=0.3)
            assert d.shape == (len(Q),) and n.shape == (len(Q), 3)
            for i in range(len(Q)):
                value, normal = c.distance(Q[i], time=0.3)
                assert d[i] == value and np.array_equal(n[i], normal)
    with pytest.raises(mbi.Error, match="P"):
        shapes[0].distances(np.zeros((4, 2)))
    with pytest.raises(mbi.Error, match="P"):
        shapes[0].distances([[0.0, float("nan"), 0.0]])
    with pytest.raises(mbi.Error, match="time"):
        shapes[0].distances(P, time=float("inf"))

def test_with_contact_refuses_what_the_step_cannot_take(scene):
    damped = mbi.Simulator(scene["U"], scene["T"], stiffness_damping=0.01)
    with pytest.raises(mbi.Error, match="stiffness_damping"):
        mbi.FramePipeline.with_contact(scene["U"], scene["T"], scene["V"], damped, [mbi.Collider.plane((0, -1, 0), (0, 1, 0))])
    sim = mbi.Simulator(scene["U"], scene["T"])
    with pytest.raises(mbi.Error, match="out of range"):
        mbi.FramePipeline.with_contact(scene["U"], scene["T"], scene["V"], sim, [], points=[10**6])
    with pytest.raises(mbi.Error, match="stiffness"):
        mbi.FramePipeline.with_contact(scene["U"], scene["T"], scene["V"], sim, [], stiffness=-1.0)


def test_from_scene_with_a_mesh_collider_steps_as_mbi_run_writes(scene, tmp_path):
    """The ground as a scene's mesh collider (shape = "mesh", a box mesh whose top is the ground):
    from_scene reads the file as `mbi run` does, and the ball rests on the mesh's top face."""
    bv, bf = box_mesh((1.0, 0.1, 1.0))
    mbi.write_surface(str(tmp_path / "floor.obj"), bv + (0.5, GROUND - 0.1, 0.5), bf.astype(np.int32))
    text = scene["path"].read_text().replace(f"ground = {GROUND!r}\n", "")
    scene["path"].write_text(text + '[[colliders]]\nshape = "mesh"\npath = "floor.obj"\n')
    run, positions, figures, size = run_and_step(scene)
    assert [f["touching"] for f in figures] == [f["contact_points"] for f in run["metrics"]["frames"]]
    assert figures[-1]["touching"] > 0
    assert abs(positions[-1][:, 1].min() - GROUND) <= 1e-3 * size
