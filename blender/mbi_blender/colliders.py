"""Colliders from Blender objects: an object marked as an mbi collider (plane, sphere, box, capsule,
mesh) becomes an mbi.Collider fitted from its bounding box (or made from its mesh) and world transform
at the run's first frame;
its animated transform over the run becomes the collider's rigid motion (motion.fit).

Shapes, in world space (the object's bounding box: local center c, half extents h scaled by the
object's scale):
  plane    through the object's origin, normal its local +Z (solid on the -Z side)
  sphere   center c, radius the largest scaled half extent
  box      center c, half extents h, axes the object's rotated axes
  capsule  along the longest axis of h, radius the largest other half extent
  mesh     the object's own mesh (modifiers not applied), triangulated, its vertices placed by the
           object's transform: a closed mesh, as mbi.Collider.mesh's level set (its voxel size chosen
           from the mesh)
"""
import numpy as np

from . import motion


def marked(scene):
    """The scene's objects marked as colliders (a cage or a bound mesh is never one)."""
    return [o for o in scene.objects if o.mbi.collider != "none" and not o.mbi.is_cage and o.mbi.cage is None]


def shape(obj, M):
    """dict(shape, fields...) of the object's collider at the world matrix M (4x4)."""
    scale = np.linalg.norm(M[:3, :3], axis=0)
    if np.any(scale <= 0):
        raise ValueError("the collider %s has a zero scale" % obj.name)
    axes = M[:3, :3] / scale  # columns: the object's unit axes in world space
    if not np.allclose(axes.T @ axes, np.eye(3), atol=1e-5) or np.linalg.det(axes) <= 0:
        raise ValueError("the collider %s is sheared or mirrored (a parent's scale): it cannot be fitted" % obj.name)
    u, _, vt = np.linalg.svd(axes)
    axes = u @ vt  # the nearest rotation: Blender's float32 matrix is orthonormal to 1e-7, mbi checks 1e-9
    corners = np.array([tuple(v) for v in obj.bound_box], dtype=np.float64)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    center = M[:3, :3] @ ((lo + hi) / 2) + M[:3, 3]
    half = (hi - lo) / 2 * scale
    kind = obj.mbi.collider
    if kind == "mesh":
        return dict(shape="mesh", V=mesh_points(obj.data) @ M[:3, :3].T + M[:3, 3], F=triangles(obj.data))
    if kind == "plane":
        return dict(shape="plane", point=M[:3, 3].copy(), normal=axes[:, 2].copy())
    if kind == "sphere":
        return dict(shape="sphere", center=center, radius=float(half.max()))
    if kind == "box":
        return dict(shape="box", center=center, half_extents=half, axes=axes.T.copy())
    k = int(np.argmax(half))
    radius = float(np.delete(half, k).max())
    reach = max(half[k] - radius, 0.0) * axes[:, k]
    return dict(shape="capsule", a=center - reach, b=center + reach, radius=radius)


def mesh_points(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def triangles(mesh):
    mesh.calc_loop_triangles()
    F = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", F)
    return F.reshape(-1, 3)


def check_apart(obj, collider, models):
    """Refuses a collider (mbi.Collider, at its first pose) that overlaps a model at rest.
    models: [(name, world rest points)]."""
    for name, P in models:
        d = collider.distances(P)[0]
        inside = np.flatnonzero(d < 0)
        if len(inside):
            deepest = int(inside[np.argmin(d[inside])])
            raise ValueError("the collider %s overlaps %s at rest: %d of its vertices inside (vertex %d %.3g m "
                             "deep); move them apart or unmark the collider"
                             % (obj.name, name, len(inside), deepest, -d[deepest]))


def probes(obj, M):
    corners = np.array([tuple(v) for v in obj.bound_box], dtype=np.float64)
    return corners @ M[:3, :3].T + M[:3, 3]


def make(mbi, obj, matrices, dt, first_frame):
    """(mbi.Collider, its shape at the first frame, its motion or None) for the object posed by matrices
    (one a frame of the run)."""
    s = shape(obj, matrices[0])
    friction = obj.mbi.friction
    try:
        if s["shape"] == "plane":
            collider = mbi.Collider.plane(s["point"], s["normal"], friction=friction)
        elif s["shape"] == "sphere":
            collider = mbi.Collider.sphere(s["center"], s["radius"], friction=friction)
        elif s["shape"] == "mesh":
            collider = mbi.Collider.mesh(s["V"], s["F"], friction=friction)
        elif s["shape"] == "box":
            collider = mbi.Collider.box(s["center"], s["half_extents"], s["axes"], friction=friction)
        else:
            collider = mbi.Collider.capsule(s["a"], s["b"], s["radius"], friction=friction)
        m = motion.fit(matrices, dt, probes(obj, matrices[0]), first_frame)
        if m is not None:
            collider = collider.moving(velocity=m["velocity"], twist_rate=m["rate"], twist_axis=m["axis"],
                                       twist_center=m["center"], start=m["start"], stop=m["stop"])
    except (mbi.Error, ValueError) as error:
        raise ValueError("the collider %s: %s" % (obj.name, error)) from error
    return collider, s, m
