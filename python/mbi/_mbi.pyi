"""Type stubs of the extension module mbi._mbi (pybind11), re-exported by the package mbi.

Shapes in docstrings: n control vertices, d = 2 or 3 dimensions, m elements, p dense points,
K = (d+1)(d+2)/2 Bezier points an element. Float arrays are float64 unless stated; array
arguments take anything numpy.asarray takes. Units are those of the inputs, SI for the simulator.
"""
import os
from typing import Any, Iterator, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int32]
PathLike = Union[str, "os.PathLike[str]"]
Method = Literal["bi", "modified-bi", "phong"]
Vector3 = Union[Sequence[float], npt.NDArray[np.floating]]

INTEGRATORS: list[str]
SOLVERS: list[str]

class Error(ValueError):
    """Every error of the libraries and every refused argument (the message names it)."""

class FileError(Error, OSError):
    """A file that could not be read or written; the message starts with the file's name."""

# ------------------------------------------------------------------ the method (core)

class Embedding:
    """Dense points located in a control mesh (read-only views)."""
    @property
    def element(self) -> IntArray: """(p,) the element holding (or nearest to) each point"""
    @property
    def bary(self) -> FloatArray: """(p, d+1) barycentric coordinates"""
    @property
    def outside(self) -> IntArray: """(k,) points outside every element"""
    @property
    def max_outside_distance(self) -> float: ...
    @property
    def gradients(self) -> FloatArray: """(m (d+1), d) each element's basis gradients"""
    @property
    def dim(self) -> int: ...
    @property
    def size(self) -> int: ...

def embed(U: ArrayLike, T: ArrayLike, P: ArrayLike) -> Embedding:
    """Locates the points P (p, d) in the mesh U (n, d), T (m, d+1)."""
def embedded_positions(U: ArrayLike, T: ArrayLike, embedding: Embedding) -> FloatArray:
    """(p, d) the embedded points back from U."""

class Deformer:
    """Embedding and the method's precompute, once; then poses to dense positions."""
    def __init__(self, U: ArrayLike, T: ArrayLike, P: ArrayLike, *, method: Method = "modified-bi",
                 alpha: Optional[float] = None, beta: float = 0.0, pin_boundary: bool = False,
                 rest_normals: Optional[ArrayLike] = None, threads: int = 0) -> None: ...
    def deform(self, X: ArrayLike, *, out: Optional[np.ndarray] = None, normals: bool = False,
               normals_out: Optional[np.ndarray] = None, dtype: Any = None) -> Any:
        """X (n, d) -> (p, d) positions, or (frames, n, d) -> (frames, p, d); with normals a
        (positions, normals) tuple; float32 out or dtype runs the fast float kernel."""
    def vjp(self, G: ArrayLike, *, out: Optional[np.ndarray] = None) -> FloatArray:
        """dL/dX (n, d) from G = dL/dpositions (p, d), or batches of them."""
    def M(self, X: ArrayLike) -> FloatArray: """((n d), d) the method's M at X"""
    def bezier(self, X: ArrayLike) -> FloatArray: """((m K), d) Bezier points at X"""
    def set_alpha(self, alpha: float) -> None: ...
    @property
    def method(self) -> str: ...
    @property
    def dim(self) -> int: ...
    @property
    def vertices(self) -> int: ...
    @property
    def elements(self) -> int: ...
    @property
    def points(self) -> int: ...
    @property
    def embedding(self) -> Embedding: ...
    @property
    def has_rest_normals(self) -> bool: ...
    @property
    def alpha(self) -> float: ...
    @property
    def beta(self) -> float: ...
    @property
    def memory_bytes(self) -> int: ...

class ModifiedBI:
    """Modified-BI's precompute (assembly, gauge, sparse Cholesky factor)."""
    def __init__(self, U: ArrayLike, T: ArrayLike, *, alpha: Optional[float] = None, beta: float = 0.0,
                 pin_boundary: bool = False, solve_path: str = "automatic", factorization: str = "automatic") -> None: ...
    def solve(self, X: ArrayLike, *, out: Optional[np.ndarray] = None) -> FloatArray: """M ((n d), d) at X (n, d)"""
    def bezier(self, X: ArrayLike, M: ArrayLike, *, out: Optional[np.ndarray] = None) -> FloatArray: ...
    def solve_transpose(self, G: ArrayLike) -> FloatArray: """dL/dX (n, d) from dL/dM ((n d), d)"""
    def set_alpha(self, alpha: float) -> None: ...
    alpha: float
    beta: float
    dim: int
    vertices: int
    elements: int
    pin_boundary: bool
    null_space_dim: int
    unknowns: int
    dense_operator: bool
    factorization: str
    factor_nonzeros: int
    memory_bytes: int

class Phong:
    """Phong deformation's M (James 2020)."""
    def __init__(self, U: ArrayLike, T: ArrayLike) -> None: ...
    def M(self, X: ArrayLike, *, out: Optional[np.ndarray] = None) -> FloatArray: ...
    def M_transpose(self, G: ArrayLike) -> FloatArray: ...
    def element_gradients(self, X: ArrayLike) -> FloatArray: ...
    def vertex_gradients(self, X: ArrayLike) -> FloatArray: ...
    dim: int
    vertices: int
    elements: int
    fallback_vertices: Any

def bezier_bi(X: ArrayLike, T: ArrayLike) -> FloatArray: """BI's Bezier points ((m K), d)"""
def bezier_points(U: ArrayLike, T: ArrayLike, X: ArrayLike, M: ArrayLike) -> FloatArray: ...
def bezier_transpose(U: ArrayLike, T: ArrayLike, G: ArrayLike) -> Tuple[FloatArray, FloatArray]:
    """(dL/dX, dL/dM) from dL/dB"""
def evaluate(B: ArrayLike, embedding: Embedding, *, out: Optional[np.ndarray] = None,
             rest_normals: Optional[ArrayLike] = None, normals_out: Optional[np.ndarray] = None,
             threads: int = 0) -> Any: """(p, d) positions (float64), with rest_normals (positions, normals)"""
def evaluate_transpose(embedding: Embedding, G: ArrayLike, elements: int, *, threads: int = 0) -> FloatArray: ...

class FastEvaluator:
    """The compact float32 kernel (AVX-512 / AVX2 picked at run time)."""
    def __init__(self, embedding: Embedding, *, threads: int = 0, simd: str = "auto") -> None: ...
    def evaluate(self, B: ArrayLike, *, out: Optional[np.ndarray] = None, normals: bool = False,
                 normals_out: Optional[np.ndarray] = None) -> Any: ...
    def set_rest_normals(self, normals: ArrayLike) -> None: ...
    def bytes_per_point(self, normals: bool = False) -> int: ...
    @staticmethod
    def supported(simd: str) -> bool: ...
    simd: str
    threads: int
    size: int
    dim: int
    elements: int
    coherent: bool
    has_rest_normals: bool

class Summary:
    mean: float
    std: float
    max: float

class DiscontinuityTable:
    """The paper's Table 2 for one pose."""
    bi: Summary
    modified_bi: Summary
    ratio: Summary
    phong: Optional[Summary]
    phong_ratio: Optional[Summary]
    e_vibr: float
    e_disc: float
    e_total: float
    faces: int

def discontinuity_table(solver: ModifiedBI, X: ArrayLike, M: ArrayLike, M_phong: Optional[ArrayLike] = None) -> DiscontinuityTable: ...
def face_discontinuity(U: ArrayLike, T: ArrayLike, X: ArrayLike, M: ArrayLike) -> FloatArray: ...
def interior_faces(T: ArrayLike) -> IntArray: ...
def boundary_faces(U: ArrayLike, T: ArrayLike) -> IntArray: ...
def validate_mesh(U: ArrayLike, T: ArrayLike) -> None: ...
def default_alpha(d: int) -> float: ...
def cholmod_available() -> bool: ...
def set_threads(n: int) -> None: """threads of every later call (0 = the cores the process may use)"""
def threads() -> int: ...
def threads_available() -> bool: ...

# ------------------------------------------------------------------ the simulator

class StepResult:
    """The outcome of Simulator.step(); false when the step failed."""
    success: bool
    message: str
    step: int
    time: float  # s, after the step
    newton_iterations: int
    solver_iterations: int
    total_ms: float
    def __bool__(self) -> bool: ...

class StaticResult:
    converged: bool
    iterations: int
    residual: float  # N
    message: str

class Simulator:
    """Co-rotational FEM of a tetrahedral mesh, SI units (m, s, kg, N, Pa, J)."""
    def __init__(self, U: ArrayLike, T: ArrayLike, *, youngs_modulus: float = 1e5, poisson_ratio: float = 0.45,
                 density: float = 1000.0, element_materials: Optional[ArrayLike] = None,
                 dt: float = ..., substeps: int = ..., gravity: Vector3 = ..., mass_damping: float = ...,
                 stiffness_damping: float = ..., integrator: Literal["backward-euler", "implicit-midpoint"] = ...,
                 newton_iterations: int = ..., newton_tolerance: float = ...,
                 solver: Literal["auto", "ldlt", "pcg"] = ..., pcg_tolerance: float = ...,
                 pcg_max_iterations: int = ..., max_energy: float = ..., ground: Optional[float] = ...,
                 ground_normal: Vector3 = ..., ground_friction: float = ...) -> None:
        """U (n, 3) rest positions (m), T (m, 4) tetrahedra; E (Pa), nu, rho (kg/m^3) or
        element_materials (m, 3) rows (E, nu, rho). dt 1/60 s, gravity (0, -9.81, 0) m/s^2 by
        default; ground: None or the height y (m) of a ground plane."""
    def set_params(self, **parameters: Any) -> None: """the keyword parameters of the constructor"""
    def fix(self, nodes: ArrayLike) -> int: """holds the nodes where they are; returns the handle"""
    def add_kinematic(self, nodes: ArrayLike, *, center: Vector3 = ..., axis: Vector3 = ...,
                      angular_velocity: float = 0.0, velocity: Vector3 = ..., start: float = 0.0,
                      stop: float = 1e300) -> int: """rigid motion: rad/s about axis through center, m/s"""
    def add_point_force(self, element: int, bary: ArrayLike, force: Vector3) -> int: """N at a material point"""
    def set_point_force(self, handle: int, force: Vector3) -> None: ...
    def add_poke(self, element: int, bary: ArrayLike, target: Vector3, stiffness: float) -> int:
        """zero-length spring (N/m) toward target (m)"""
    def set_poke_target(self, handle: int, target: Vector3) -> None: ...
    def remove(self, handle: int) -> None: ...
    def has_handle(self, handle: int) -> bool: ...
    def step(self) -> StepResult: """advances by dt (s)"""
    def solve_static(self, max_iterations: int = 100, tolerance: float = 0.0) -> StaticResult: ...
    def reset(self) -> None: ...
    def set_positions(self, X: ArrayLike) -> None: """(n, 3) m"""
    def set_velocities(self, V: ArrayLike) -> None: """(n, 3) m/s"""
    def elastic_forces(self) -> FloatArray: """(n, 3) N"""
    def kinetic_energy(self) -> float: """J"""
    def elastic_energy(self) -> float: """J"""
    def gravity_energy(self) -> float: """J"""
    def volume(self) -> float: """m^3"""
    def rest_volume(self) -> float: """m^3"""
    def linear_momentum(self) -> FloatArray: """(3,) kg m/s"""
    def angular_momentum(self) -> FloatArray: """(3,) kg m^2/s"""
    @property
    def positions(self) -> FloatArray: """(n, 3) m, a copy"""
    @property
    def velocities(self) -> FloatArray: """(n, 3) m/s, a copy"""
    @property
    def rest_positions(self) -> FloatArray: ...
    @property
    def masses(self) -> FloatArray: """(n,) kg"""
    @property
    def time(self) -> float: """s"""
    @property
    def step_count(self) -> int: ...
    @property
    def nodes(self) -> int: ...
    @property
    def elements(self) -> int: ...
    @property
    def dt(self) -> float: ...
    @property
    def solver(self) -> str: ...

# ------------------------------------------------------------------ the frame pipeline

class HandleDriver:
    """Control vertices dragged without physics; M solved with the positions."""
    def __init__(self, U: ArrayLike, T: ArrayLike, handles: ArrayLike, *, mode: Literal["hard", "soft"] = "hard",
                 alpha: Optional[float] = None, beta: float = 0.0, pin_boundary: bool = False, gamma: float = 0.0,
                 regularization: float = 1e-6) -> None: ...
    def set_targets(self, targets: ArrayLike) -> None: """(handles, d) positions"""
    @property
    def handles(self) -> list[int]: ...

class GivenDriver:
    """Poses from outside: X (n, d) changed by set(), or a sequence (frames, n, d)."""
    def __init__(self, X: ArrayLike) -> None: ...
    def set(self, X: ArrayLike) -> None: ...

class FrameResult:
    ok: bool
    message: str
    frame: int
    def __bool__(self) -> bool: ...

class FramePipeline:
    """Per frame: drive the control mesh, solve M, Bezier points, dense points (CPU, float64)."""
    def __init__(self, U: ArrayLike, T: ArrayLike, P: ArrayLike,
                 driver: Union[None, Simulator, HandleDriver, GivenDriver] = None, *, method: Method = "modified-bi",
                 alpha: Optional[float] = None, beta: float = 0.0, pin_boundary: bool = False,
                 rest_normals: Optional[ArrayLike] = None) -> None: ...
    def step(self, evaluate: bool = True) -> FrameResult: """the next frame (frame 0 first: the initial pose)"""
    def run(self, frames: int) -> FloatArray: """(frames, p, d) positions of `frames` steps"""
    def reset(self) -> None: ...
    def set_method(self, method: Method) -> None: ...
    def set_alpha(self, alpha: float) -> None: ...
    def evaluate_with(self, method: Method) -> FloatArray: ...
    @property
    def frame(self) -> int: ...
    @property
    def positions(self) -> FloatArray: """(p, d)"""
    @property
    def normals(self) -> FloatArray: ...
    @property
    def control_positions(self) -> FloatArray: """(n, d)"""
    @property
    def M(self) -> FloatArray: """((n d), d)"""
    @property
    def timings(self) -> dict[str, float]: """ms of the last frame's phases"""
    @property
    def method(self) -> str: ...
    @property
    def driver(self) -> str: ...
    @property
    def dim(self) -> int: ...

# ------------------------------------------------------------------ files

class Surface:
    """A surface as a file holds it, with the file's other attributes kept for write_surface."""
    def __init__(self, V: ArrayLike, F: Optional[ArrayLike] = None, N: Optional[ArrayLike] = None) -> None: ...
    V: FloatArray  # (n, 3)
    F: IntArray  # (t, 3)
    N: Optional[FloatArray]  # (n, 3) unit normals
    @property
    def polygons(self) -> list[list[int]]: ...
    @property
    def has_attributes(self) -> bool: ...
    def with_positions(self, V: ArrayLike, N: Optional[ArrayLike] = None) -> "Surface": ...

def read_surface(path: PathLike) -> Surface: """.obj, .off, .ply, .stl"""
def write_surface(path: PathLike, mesh: Union[Surface, ArrayLike], F: Optional[ArrayLike] = None, *,
                  N: Optional[ArrayLike] = None, encoding: Literal["as_read", "ascii", "binary"] = "as_read") -> None: ...
def read_points(path: PathLike) -> FloatArray: """(n, d) from .txt / .xyz"""
def write_points(path: PathLike, P: ArrayLike) -> None: ...

class ControlMesh:
    @property
    def U(self) -> FloatArray: """(n, d)"""
    @property
    def T(self) -> IntArray: """(m, d+1)"""
    @property
    def notes(self) -> list[str]: ...
    @property
    def dim(self) -> int: ...
    def __iter__(self) -> Iterator[np.ndarray]: ...

def read_control_mesh(path: PathLike) -> ControlMesh: """TetGen, .msh, .vtk, .vtu"""
def read_positions(path: PathLike) -> FloatArray: ...
def write_tetgen(base: PathLike, U: ArrayLike, T: ArrayLike) -> None: ...
def write_vtk(path: PathLike, U: ArrayLike, T: ArrayLike, point_vectors: Optional[ArrayLike] = None,
              point_data: str = "displacement") -> None: ...

class PointCache:
    @property
    def frames(self) -> FloatArray: """(frames, n, 3)"""
    start_frame: float
    sample_rate: float
    times: list[float]

def read_point_cache(path: PathLike) -> PointCache: """.pc2 or .mdd"""
def write_point_cache(path: PathLike, frames: ArrayLike, *, start_frame: float = 0.0, sample_rate: float = 1.0,
                      times: Optional[Sequence[float]] = None) -> None: ...
def read_pvd(path: PathLike) -> list[Tuple[float, str]]: ...
def read_trajectory(spec: PathLike) -> Tuple[FloatArray, list[float]]: ...

# ------------------------------------------------------------------ cages

class Cage:
    @property
    def U(self) -> FloatArray: ...
    @property
    def T(self) -> IntArray: ...
    dim: int
    cell_size: float
    min_dihedral_deg: float
    outside_points: int
    seconds: float
    mesher: str
    tetgen_switches: str
    def __iter__(self) -> Iterator[np.ndarray]: ...

def cage(V: ArrayLike, F: Optional[ArrayLike] = None, *, vertices: int = 200,
         mesher: Literal["voxel", "tetgen"] = "voxel", force_3d: bool = False) -> Cage: ...

def _run_scene(path: str, out: Optional[str] = None, frames: int = 0, mesh: Optional[str] = None,
               method: Optional[str] = None, gpu: Optional[str] = None, force: bool = False,
               force_3d: bool = False) -> dict[str, Any]: ...
