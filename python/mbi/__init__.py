"""mbi: physics-driven deformation of dense meshes by modified barycentric interpolation.

Arrays in, arrays out (numpy). Shapes: U, X (n, d) control vertices (rest, deformed), d = 2 or 3;
T (m, d+1) elements (0-based, any integer type); P (p, d) dense points; M ((n d), d) per-vertex
matrices; B ((m K), d) element Bezier points, K = (d+1)(d+2)/2. Positions are in the units of U.

    import mbi
    deformer = mbi.Deformer(U, T, P, method="modified-bi")   # embedding + precompute, once
    positions = deformer.deform(X)                           # per pose: (p, d)
    dX = deformer.vjp(dL_dpositions)                         # dL/dX, exact

Every error of the libraries and every refused argument raises mbi.Error (a ValueError) with the
message of the C++ library. PyTorch autograd: mbi.torch (imported on its own). docs/python.md
documents the whole API.
"""
from ._mbi import (
    Deformer,
    DiscontinuityTable,
    Embedding,
    Error,
    FastEvaluator,
    ModifiedBI,
    Phong,
    Summary,
    bezier_bi,
    bezier_points,
    bezier_transpose,
    boundary_faces,
    cholmod_available,
    default_alpha,
    discontinuity_table,
    embed,
    embedded_positions,
    evaluate,
    evaluate_transpose,
    face_discontinuity,
    interior_faces,
    set_threads,
    threads,
    threads_available,
    validate_mesh,
)
from .meshes import box_mesh

__version__ = "0.1.0"

METHODS = ("bi", "modified-bi", "phong")

__all__ = [
    "Deformer", "DiscontinuityTable", "box_mesh", "Embedding", "Error", "FastEvaluator", "METHODS", "ModifiedBI",
    "Phong", "Summary", "bezier_bi", "bezier_points", "bezier_transpose", "boundary_faces",
    "cholmod_available", "default_alpha", "discontinuity_table", "embed", "embedded_positions",
    "evaluate", "evaluate_transpose", "face_discontinuity", "interior_faces", "set_threads", "threads", "threads_available", "validate_mesh",
]
