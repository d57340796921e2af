"""Type stubs of the extension module mbi._mbi (pybind11), re-exported by the package mbi.

Shapes in docstrings: n control vertices, d = 2 or 3 dimensions, m elements, p dense points,
K = (d+1)(d+2)/2 Bezier points an element. Float arrays are float64 unless stated; array
arguments take anything numpy.asarray takes. Units are those of the inputs, SI for the simulator.
Array shapes are not part of the types: a batch (frames, n, d) gives the same array type as a
pose (n, d). Where the result's type depends on an argument (out=, normals=, dtype=), overloads
give it.
"""
import os
import types
from typing import Any, Iterator, Literal, Optional, Sequence, Tuple, Type, TypeVar, Union, overload

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
Float32Array = npt.NDArray[np.float32]
IntArray = npt.NDArray[np.int32]
AnyArray = npt.NDArray[Any]
PathLike = Union[str, "os.PathLike[str]"]
Method = Literal["bi", "modified-bi", "phong"]
Integrator = Literal["backward-euler", "implicit-midpoint"]
Solver = Literal["auto", "ldlt", "pcg"]
Simd = Literal["auto", "avx512", "avx2", "portable"]
Vector3 = Union[Sequence[float], npt.NDArray[np.floating[Any]]]
Out = TypeVar("Out", bound=AnyArray)
Float64Type = Union[Type[np.float64], Literal["float64"]]
Float32Type = Union[Type[np.float32], Literal["float32"]]
MemorySize = Union[int, float, str, None]
"""bytes, or a size such as "8G" or "512M" (K, M, G, T: powers of 1024); None: the memory available"""

INTEGRATORS: Tuple[Integrator, ...]
SOLVERS: Tuple[Solver, ...]
_timing: Optional[types.ModuleType]
"""The overhead benchmark's C++ clocks (python/bench/overhead.py): a submodule in a module built
with -DMBI_PYTHON_TIMING=ON, None in the shipped module."""

class Error(ValueError):
    """Every error of the libraries and every refused argument (the message names it)."""

class FileError(Error, OSError):
    """A file that could not be read or written; the message starts with the file's name."""

class OutsideWarning(UserWarning):
    """Dense points outside the control mesh, extrapolated from the nearest element."""

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
    def __len__(self) -> int: ...

def embed(U: ArrayLike, T: ArrayLike, P: ArrayLike, *, max_outside: Optional[float] = None) -> Embedding:
    """Locates the points P (p, d) in the mesh U (n, d), T (m, d+1); outside points warn (OutsideWarning)."""
def embedded_positions(U: ArrayLike, T: ArrayLike, embedding: Embedding) -> FloatArray:
    """(p, d) the embedded points back from U."""

class Deformer:
    """Embedding and the method's precompute, once; then poses to dense positions."""
    def __init__(self, U: ArrayLike, T: ArrayLike, P: ArrayLike, *, method: Method = "modified-bi",
                 alpha: Optional[float] = None, beta: float = 0.0, pin_boundary: bool = False,
                 rest_normals: Optional[ArrayLike] = None, threads: int = 0,
                 max_outside: Optional[float] = None, max_memory: MemorySize = None) -> None: ...
    @property
    def outside_points(self) -> int: """points outside the control mesh"""
    @property
    def max_outside_distance(self) -> float: """the farthest outside point's distance to the mesh (units of P)"""
    # mypy takes Type[np.float64] and Type[np.float32] (aliases of one generic class) to overlap
    @overload
    def deform(  # type: ignore[misc]
            self, X: ArrayLike, *, out: None = None, normals: Literal[False] = False, normals_out: None = None,
            dtype: Optional[Float64Type] = None) -> FloatArray:
        """X (n, d) -> (p, d) positions, or (frames, n, d) -> (frames, p, d); with normals a
        (positions, normals) tuple; float32 out or dtype runs the fast float kernel."""
    @overload
    def deform(self, X: ArrayLike, *, out: None = None, normals: Literal[False] = False, normals_out: None = None,
               dtype: Float32Type) -> Float32Array: ...
    @overload
    def deform(self, X: ArrayLike, *, out: Out, normals: Literal[False] = False, normals_out: None = None,
               dtype: Any = None) -> Out: ...
    @overload
    def deform(self, X: ArrayLike, *, out: Optional[AnyArray] = None, normals: Literal[True],
               normals_out: Optional[AnyArray] = None, dtype: Any = None) -> Tuple[AnyArray, AnyArray]: ...
    @overload
    def deform(self, X: ArrayLike, *, out: Optional[AnyArray] = None, normals: bool = False, normals_out: AnyArray,
               dtype: Any = None) -> Tuple[AnyArray, AnyArray]: ...
    @overload
    def vjp(self, G: ArrayLike, *, out: None = None) -> FloatArray:
        """dL/dX (n, d) from G = dL/dpositions (p, d), or batches of them; C order, as X."""
    @overload
    def vjp(self, G: ArrayLike, *, out: Out) -> Out:
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
                 pin_boundary: bool = False, solve_path: Literal["automatic", "sparse", "dense", "iterative"] = "automatic",
                 factorization: Literal["automatic", "eigen", "cholmod"] = "automatic",
                 max_memory: MemorySize = None) -> None: ...
    def solve(self, X: ArrayLike, *, out: Optional[AnyArray] = None) -> FloatArray: """M ((n d), d) at X (n, d)"""
    def bezier(self, X: ArrayLike, M: ArrayLike, *, out: Optional[AnyArray] = None) -> FloatArray: ...
    def solve_transpose(self, G: ArrayLike) -> FloatArray: """dL/dX (n, d) from dL/dM ((n d), d)"""
    def set_alpha(self, alpha: float) -> None: ...
    @property
    def alpha(self) -> float: ...
    @property
    def beta(self) -> float: ...
    @property
    def dim(self) -> int: ...
    @property
    def vertices(self) -> int: ...
    @property
    def elements(self) -> int: ...
    @property
    def pin_boundary(self) -> bool: ...
    @property
    def null_space_dim(self) -> int: ...
    @property
    def unknowns(self) -> int: ...
    @property
    def dense_operator(self) -> bool: ...
    @property
    def factorization(self) -> str: ...
    @property
    def factor_nonzeros(self) -> int: ...
    @property
    def factor_stored_values(self) -> int: ...
    @property
    def factor_index_bytes(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...

class MemoryEstimate:
    """The estimated peak memory of a modified-BI run and its parts (bytes, counts)."""
    @property
    def unknowns(self) -> int: ...
    @property
    def matrix_nonzeros(self) -> int: ...
    @property
    def factor_nonzeros(self) -> int: ...
    @property
    def factor_flops(self) -> float: ...
    @property
    def ordering(self) -> str: ...
    @property
    def factor_bytes(self) -> float: ...
    @property
    def assembly_bytes(self) -> float: ...
    @property
    def dense_operator_bytes(self) -> float: ...
    @property
    def model_bytes(self) -> float: ...
    @property
    def process_bytes(self) -> float: ...
    @property
    def peak_bytes(self) -> float: ...

def estimate_memory(U: ArrayLike, T: ArrayLike, dense_points: int = 0, *, pin_boundary: bool = False,
                    solve_path: Literal["automatic", "sparse", "dense", "iterative"] = "automatic",
                    factorization: Literal["automatic", "eigen", "cholmod"] = "automatic") -> MemoryEstimate:
    """ModifiedBI(U, T)'s peak before any numeric work (the factor's symbolic analysis)"""
def memory_limit(max_memory: MemorySize = None) -> Tuple[float, str]:
    """(bytes, what they are): max_memory, else MemAvailable or the control group's limit"""

class Phong:
    """Phong deformation's M (James 2020)."""
    def __init__(self, U: ArrayLike, T: ArrayLike) -> None: ...
    def M(self, X: ArrayLike, *, out: Optional[AnyArray] = None) -> FloatArray: ...
    def M_transpose(self, G: ArrayLike) -> FloatArray: ...
    def element_gradients(self, X: ArrayLike) -> FloatArray: ...
    def vertex_gradients(self, X: ArrayLike) -> FloatArray: ...
    @property
    def dim(self) -> int: ...
    @property
    def vertices(self) -> int: ...
    @property
    def elements(self) -> int: ...
    @property
    def fallback_vertices(self) -> int: ...

def bezier_bi(X: ArrayLike, T: ArrayLike) -> FloatArray: """BI's Bezier points ((m K), d)"""
def bezier_points(U: ArrayLike, T: ArrayLike, X: ArrayLike, M: ArrayLike) -> FloatArray: ...
def bezier_transpose(U: ArrayLike, T: ArrayLike, G: ArrayLike) -> Tuple[FloatArray, FloatArray]:
    """(dL/dX, dL/dM) from dL/dB"""
@overload
def evaluate(B: ArrayLike, embedding: Embedding, *, out: Optional[AnyArray] = None, rest_normals: None = None,
             normals_out: None = None, threads: int = 0) -> FloatArray:
    """(p, d) positions (float64), with rest_normals (positions, normals)"""
@overload
def evaluate(B: ArrayLike, embedding: Embedding, *, out: Optional[AnyArray] = None, rest_normals: ArrayLike,
             normals_out: Optional[AnyArray] = None, threads: int = 0) -> Tuple[FloatArray, FloatArray]: ...
def evaluate_transpose(embedding: Embedding, G: ArrayLike, elements: int, *, threads: int = 0) -> FloatArray: ...

class FastEvaluator:
    """The compact float32 kernel (AVX-512 / AVX2 picked at run time)."""
    def __init__(self, embedding: Embedding, *, threads: int = 0, simd: Simd = "auto") -> None: ...
    @overload
    def evaluate(self, B: ArrayLike, *, out: Optional[AnyArray] = None, normals: Literal[False] = False,
                 normals_out: None = None) -> Float32Array: """(p, d) float32 positions"""
    @overload
    def evaluate(self, B: ArrayLike, *, out: Optional[AnyArray] = None, normals: Literal[True],
                 normals_out: Optional[AnyArray] = None) -> Tuple[Float32Array, Float32Array]: ...
    @overload
    def evaluate(self, B: ArrayLike, *, out: Optional[AnyArray] = None, normals: bool = False,
                 normals_out: AnyArray) -> Tuple[Float32Array, Float32Array]: ...
    def set_rest_normals(self, normals: ArrayLike) -> None: ...
    def bytes_per_point(self, normals: bool = False) -> int: ...
    @staticmethod
    def supported(simd: Simd) -> bool: ...
    @property
    def simd(self) -> str: ...
    @property
    def threads(self) -> int: ...
    @property
    def size(self) -> int: ...
    @property
    def dim(self) -> int: ...
    @property
    def elements(self) -> int: ...
    @property
    def coherent(self) -> bool: ...
    @property
    def sorted_by_element(self) -> bool: ...
    @property
    def has_rest_normals(self) -> bool: ...

class Summary:
    @property
    def mean(self) -> float: ...
    @property
    def std(self) -> float: ...
    @property
    def max(self) -> float: ...

class DiscontinuityTable:
    """The paper's Table 2 for one pose."""
    @property
    def bi(self) -> Summary: ...
    @property
    def modified_bi(self) -> Summary: ...
    @property
    def ratio(self) -> Summary: ...
    @property
    def phong(self) -> Optional[Summary]: ...
    @property
    def phong_ratio(self) -> Optional[Summary]: ...
    @property
    def e_vibr(self) -> float: ...
    @property
    def e_disc(self) -> float: ...
    @property
    def e_total(self) -> float: ...
    @property
    def faces(self) -> int: ...

def discontinuity_table(solver: ModifiedBI, X: ArrayLike, M: ArrayLike, M_phong: Optional[ArrayLike] = None) -> DiscontinuityTable: ...
def face_discontinuity(U: ArrayLike, T: ArrayLike, X: ArrayLike, M: ArrayLike) -> FloatArray: ...
def interior_faces(T: ArrayLike) -> IntArray: ...
def boundary_faces(U: ArrayLike, T: ArrayLike) -> IntArray: ...
def validate_mesh(U: ArrayLike, T: ArrayLike) -> None: ...
class HarmonicExtension:
    """The free nodes of a control mesh moved with its fixed ones (harmonic extension of their displacement)."""
    def __init__(self, U: ArrayLike, T: ArrayLike, fixed: Optional[ArrayLike] = None) -> None: ...
    def apply(self, X: ArrayLike) -> FloatArray: """(n, d): X with the free nodes' rows replaced"""
    @property
    def free_nodes(self) -> IntArray: ...
    @property
    def fixed_nodes(self) -> IntArray: ...
    @property
    def memory_bytes(self) -> int: ...

def default_alpha(d: int) -> float: ...
def cholmod_available() -> bool: ...
def set_threads(n: int) -> None: """threads of every later call (0 = the cores the process may use)"""
def threads() -> int: ...
def threads_available() -> bool: ...

# ------------------------------------------------------------------ the simulator

class StepResult:
    """The outcome of Simulator.step(); false when the step failed."""
    @property
    def success(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def step(self) -> int: ...
    @property
    def time(self) -> float: """s, after the step"""
    @property
    def newton_iterations(self) -> int: ...
    @property
    def solver_iterations(self) -> int: ...
    @property
    def total_ms(self) -> float: ...
    def __bool__(self) -> bool: ...

class StaticResult:
    @property
    def converged(self) -> bool: ...
    @property
    def iterations(self) -> int: ...
    @property
    def residual(self) -> float: """N"""
    @property
    def message(self) -> str: ...

class Simulator:
    """Co-rotational FEM of a tetrahedral mesh, SI units (m, s, kg, N, Pa, J)."""
    def __init__(self, U: ArrayLike, T: ArrayLike, *, youngs_modulus: float = 1e5, poisson_ratio: float = 0.45,
                 density: float = 1000.0, element_materials: Optional[ArrayLike] = None,
                 dt: float = ..., substeps: int = ..., gravity: Vector3 = ..., mass_damping: float = ...,
                 stiffness_damping: float = ..., integrator: Integrator = ...,
                 newton_iterations: int = ..., newton_tolerance: float = ...,
                 solver: Solver = ..., pcg_tolerance: float = ...,
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

class Collider:
    """A rigid collider (plane, sphere, box, capsule, closed triangle mesh) that the dense points touch, static or
    moving; m, s."""
    @staticmethod
    def plane(point: Vector3, normal: Vector3, *, friction: float = 0.0) -> Collider:
        """solid where normal . (x - point) < 0"""
    @staticmethod
    def sphere(center: Vector3, radius: float, *, friction: float = 0.0) -> Collider: ...
    @staticmethod
    def box(center: Vector3, half_extents: Vector3, axes: Optional[ArrayLike] = None, *,
            friction: float = 0.0) -> Collider: """axes: (3, 3), its rows the box's unit axes"""
    @staticmethod
    def capsule(a: Vector3, b: Vector3, radius: float, *, friction: float = 0.0) -> Collider: ...
    @staticmethod
    def mesh(V: ArrayLike, F: ArrayLike, *, friction: float = 0.0, voxel_size: Optional[float] = None,
             band_voxels: float = 3.0) -> Collider:
        """a closed triangle mesh as a signed distance field; distances within a voxel"""
    def moving(self, *, velocity: Vector3 = ..., twist_rate: float = 0.0, twist_axis: Vector3 = ...,
               twist_center: Vector3 = ..., start: float = 0.0, stop: float = 1e300) -> Collider:
        """the collider moving rigidly from its pose at start (s): velocity m/s, twist_rate rad/s"""
    def distance(self, p: Vector3, time: float = 0.0) -> Tuple[float, FloatArray]:
        """(signed distance (m, < 0 inside), unit outward normal) at p"""
    def distances(self, P: ArrayLike, time: float = 0.0) -> Tuple[FloatArray, FloatArray]:
        """(signed distances (p,) (m, < 0 inside), unit outward normals (p, 3)) at the points P (p, 3)"""
    @property
    def shape(self) -> Literal["plane", "sphere", "box", "capsule", "mesh"]: ...
    @property
    def friction(self) -> float: ...
    @property
    def radius(self) -> float: ...

class FrameResult:
    @property
    def ok(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def frame(self) -> int: ...
    def __bool__(self) -> bool: ...

class FramePipeline:
    """Per frame: drive the control mesh, solve M, Bezier points, dense points (CPU, float64)."""
    def __init__(self, U: ArrayLike, T: ArrayLike, P: ArrayLike,
                 driver: Union[None, Simulator, HandleDriver, GivenDriver] = None, *, method: Method = "modified-bi",
                 alpha: Optional[float] = None, beta: float = 0.0, pin_boundary: bool = False,
                 rest_normals: Optional[ArrayLike] = None, max_outside: Optional[float] = None) -> None: ...
    @property
    def outside_points(self) -> int: """points outside the control mesh"""
    @property
    def max_outside_distance(self) -> float: """the farthest outside point's distance to the mesh (units of P)"""
    @staticmethod
    def with_contact(U: ArrayLike, T: ArrayLike, P: ArrayLike, simulator: Simulator, colliders: Sequence[Collider], *,
                     stiffness: Optional[float] = None, points: Optional[ArrayLike] = None, method: Method = "modified-bi",
                     alpha: Optional[float] = None, beta: float = 0.0, pin_boundary: bool = False) -> FramePipeline:
        """the simulator steps with contact at the dense points P (or the rows `points`) against colliders"""
    @staticmethod
    def from_scene(path: PathLike, *, method: Optional[Method] = None) -> FramePipeline:
        """a scene file's pipeline as `mbi run` builds it (contact keys included)"""
    @property
    def contact(self) -> Optional[dict[str, Any]]:
        """the last frame's contact at the dense points (touching, newton_iterations, ...), or None"""
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
    def __iter__(self) -> Iterator[AnyArray]: """V, F"""

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
    def __iter__(self) -> Iterator[AnyArray]: ...

def read_control_mesh(path: PathLike) -> ControlMesh: """TetGen, .msh, .vtk, .vtu"""
def read_positions(path: PathLike) -> FloatArray: ...
def write_tetgen(base: PathLike, U: ArrayLike, T: ArrayLike) -> None: ...
def write_vtk(path: PathLike, U: ArrayLike, T: ArrayLike, point_vectors: Optional[ArrayLike] = None,
              point_data: str = "displacement") -> None: ...

class PointCache:
    @property
    def frames(self) -> FloatArray: """(frames, n, 3)"""
    @property
    def start_frame(self) -> float: ...
    @property
    def sample_rate(self) -> float: ...
    @property
    def times(self) -> list[float]: ...

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
    @property
    def dim(self) -> int: ...
    @property
    def cell_size(self) -> float: ...
    @property
    def min_dihedral_deg(self) -> float: ...
    @property
    def outside_points(self) -> int: ...
    @property
    def seconds(self) -> float: ...
    @property
    def mesher(self) -> str: ...
    @property
    def tetgen_switches(self) -> str: ...
    def __iter__(self) -> Iterator[AnyArray]: ...

def cage(V: ArrayLike, F: Optional[ArrayLike] = None, *, vertices: int = 200,
         mesher: Literal["voxel", "tetgen"] = "voxel", force_3d: bool = False) -> Cage: ...

def _run_scene(path: str, out: Optional[str] = None, frames: int = 0, mesh: Optional[str] = None,
               method: Optional[str] = None, gpu: Optional[str] = None, force: bool = False,
               force_3d: bool = False) -> dict[str, Any]: ...
