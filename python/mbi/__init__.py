"""mbi: physics-driven deformation of dense meshes by modified barycentric interpolation.

Arrays in, arrays out (numpy). Shapes: U, X (n, d) control vertices (rest, deformed), d = 2 or 3;
T (m, d+1) elements (0-based, any integer type); P (p, d) dense points; M ((n d), d) per-vertex
matrices; B ((m K), d) element Bezier points, K = (d+1)(d+2)/2. Positions are in the units of U.

    import mbi
    deformer = mbi.Deformer(U, T, P, method="modified-bi")   # embedding + precompute, once
    positions = deformer.deform(X)                           # per pose: (p, d)
    dX = deformer.vjp(dL_dpositions)                         # dL/dX, exact

Beyond the method: mbi.Simulator (co-rotational FEM) and mbi.FramePipeline (simulator, dragged
handles or given poses to dense points each frame); files (read_surface, write_surface keeping
the file's attributes, read_control_mesh, point caches); mbi.cage (a control mesh around a model);
mbi.run_scene (a scene file, as `mbi run`); mbi.batch (runs on a Dask cluster).

Every error of the libraries and every refused argument raises mbi.Error (a ValueError) with the
message of the C++ library; a file that cannot be read or written raises mbi.FileError (an
mbi.Error and an OSError) naming it. PyTorch autograd: mbi.torch (imported on its own).
docs/python.md documents the whole API; _mbi.pyi gives editors and type checkers the signatures of the module.
"""
from typing import Literal, Tuple

from . import _checks

_checks.require_module()  # an ImportError naming the interpreter the module was built for
_checks.require_numpy()

from . import _errors, _mbi  # noqa: E402

_errors.shorten_type_errors(_mbi)  # a call matching no signature: a one-line TypeError naming the argument

from ._mbi import (  # noqa: E402
    INTEGRATORS,
    SOLVERS,
    Cage,
    Collider,
    ControlMesh,
    Deformer,
    DiscontinuityTable,
    Embedding,
    Error,
    FastEvaluator,
    FileError,
    FramePipeline,
    FrameResult,
    GivenDriver,
    HandleDriver,
    HarmonicExtension,
    MemoryEstimate,
    ModifiedBI,
    OutsideWarning,
    Phong,
    PointCache,
    Simulator,
    StaticResult,
    StepResult,
    Summary,
    Surface,
    bezier_bi,
    bezier_points,
    bezier_transpose,
    boundary_faces,
    cage,
    cholmod_available,
    default_alpha,
    discontinuity_table,
    embed,
    embedded_positions,
    estimate_memory,
    evaluate,
    evaluate_transpose,
    face_discontinuity,
    interior_faces,
    memory_limit,
    read_control_mesh,
    read_point_cache,
    read_points,
    read_positions,
    read_pvd,
    read_surface,
    read_trajectory,
    set_threads,
    threads,
    threads_available,
    validate_mesh,
    write_point_cache,
    write_points,
    write_surface,
    write_tetgen,
    write_vtk,
)
from .meshes import box_mesh  # noqa: E402
from .scenes import run_scene  # noqa: E402
from . import batch  # noqa: E402  (plain Python: importing it needs no Dask)

__version__ = "0.1.0"  # the project's version (CMakeLists.txt; pip's metadata too)

Method = Literal["bi", "modified-bi", "phong"]
METHODS: Tuple[Method, ...] = ("bi", "modified-bi", "phong")

__all__ = [
    "Cage", "Collider", "ControlMesh", "Deformer", "DiscontinuityTable", "Embedding", "Error", "FastEvaluator",
    "FileError", "FramePipeline", "FrameResult", "GivenDriver", "HandleDriver", "HarmonicExtension", "INTEGRATORS",
    "METHODS", "MemoryEstimate",
    "ModifiedBI", "OutsideWarning", "Phong", "PointCache", "SOLVERS", "Simulator", "StaticResult", "StepResult",
    "Summary", "Surface", "batch", "bezier_bi", "bezier_points", "bezier_transpose", "boundary_faces", "box_mesh",
    "cage", "cholmod_available", "default_alpha", "discontinuity_table", "embed", "embedded_positions", "estimate_memory", "evaluate",
    "evaluate_transpose", "face_discontinuity", "interior_faces", "memory_limit", "read_control_mesh", "read_point_cache",
    "read_points", "read_positions", "read_pvd", "read_surface", "read_trajectory", "run_scene", "set_threads",
    "threads", "threads_available", "validate_mesh", "write_point_cache", "write_points", "write_surface",
    "write_tetgen", "write_vtk",
]
