"""Side by side inside Blender: the mbi add-on's live path against Mesh Deform (precision 5) and
Surface Deform on the same model and cage; bind time, time per frame, memory added.

    MBI_PYTHON_DIR=build/release/python MBI_MODELS_DIR=../shared/models \\
    blender -b --factory-startup --python bench/blender/side_by_side.py -- \\
        [--model stanford-bunny] [--subdivide 0 2] [--vertices 1000] [--frames 30] [--runs 3] [--processes 1]

The cage is `mbi.cage` of about --vertices nodes around the model; Mesh Deform and Surface Deform
get its boundary (a closed triangle mesh). Every node of the cage is animated by a keyframed shape
key (a bend growing over the frames; the boundary cage gets the same motion of its nodes). Each
(model, subdivision, method) runs in a fresh Blender process (--one), so memory is that method's:
  floor          Blender's own cost: the model's mesh re-evaluated each frame, no deformation
  mbi            the add-on: bind operator (embedding, precompute, first write), live attribute
  mbi-boundary   the same with only the cage's boundary animated (the interior by the harmonic extension)
  meshdeform     Mesh Deform modifier, precision 5, bind operator plus its evaluation
  surfacedeform  Surface Deform modifier, bind operator plus its evaluation (it refuses an edge of more
                 than two faces: the faces on such an edge get their own copies of their vertices)
Per frame: wall time of scene.frame_set (the cage's key, the deformation, the model's
re-evaluation), median and min over --runs passes of --frames frames. Quality (models up to 200K
vertices): the change of the dihedral angles at the model's edges at the full 90-degree bend against
the same bend applied to the model itself, mean and 99th percentile, degrees. Memory: resident set size
after the frames minus before the bind, each read after the allocators (glibc's, Blender's jemalloc)
hand free pages back (live memory, not free heap). A method that takes over --limit s (default 300) is
reported as skipped. Subdivision: Catmull-Clark (Blender's Subdivision Surface, applied).
--processes N runs each (model, subdivision, method) in N fresh processes and reports the median of
each figure.
"""
import argparse
import ctypes
import gc
import json
import os
import subprocess
import sys
import tempfile
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
METHODS = ("floor", "mbi", "mbi-boundary", "meshdeform", "surfacedeform")


def release_free_heap():
    """Hands free heap pages back to the system: glibc's (malloc_trim) and jemalloc's, which
    Debian's Blender links and which otherwise keeps freed pages for seconds (its decay)."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass
    process = ctypes.CDLL(None)
    if hasattr(process, "mallctl"):  # jemalloc: this thread's cache, then every arena's free pages
        for name in (b"thread.tcache.flush", b"arena.4096.purge"):
            process.mallctl(name, None, None, None, ctypes.c_size_t(0))


def rss_mb():
    """Resident set size after a garbage collection and the allocators handing free heap pages
    back, so that the figure is what is live and not what an allocator happens to keep; done the
    same for every method."""
    gc.collect()
    release_free_heap()
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def load_mbi():
    sys.path.insert(0, os.path.join(HERE, "..", "..", "blender"))
    import mbi_blender
    mbi_blender.register()
    from mbi_blender import module
    return module.load()


def model_object(mbi, path, subdivide):
    V, F = mbi.read_surface(path)
    mesh = bpy.data.meshes.new("model")
    mesh.from_pydata(V.tolist(), [], F.tolist())
    obj = bpy.data.objects.new("model", mesh)
    bpy.context.collection.objects.link(obj)
    if subdivide:
        modifier = obj.modifiers.new("subdivide", "SUBSURF")
        modifier.levels = modifier.render_levels = subdivide
        with bpy.context.temp_override(object=obj, active_object=obj):
            bpy.ops.object.modifier_apply(modifier="subdivide")
    return obj


def bend(U, amount, frame=None):
    """Points bent about y over the frame's x extent by amount x 90 degrees (frame: the cage's nodes)."""
    frame = U if frame is None else frame
    if amount == 0:
        return U.copy()
    c, length = frame.mean(axis=0), np.ptp(frame[:, 0])
    radius = length / (amount * np.pi / 2)
    theta = (U[:, 0] - c[0]) / radius
    r = radius - (U[:, 2] - c[2])
    X = U.copy()
    X[:, 0] = c[0] + r * np.sin(theta)
    X[:, 2] = c[2] + radius - r * np.cos(theta)
    return X


def cage_object(name, U, faces, frames, moving=None):
    """The cage with a keyframed bend of its nodes (moving: only those move, bent as the whole cage)."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(U.tolist(), [], faces.tolist())
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.collection.objects.link(obj)
    obj.shape_key_add(name="Basis", from_mix=False)
    key = obj.shape_key_add(name="bend", from_mix=False)
    X = bend(U, 1.0)
    if moving is not None:
        X = np.where(moving[:, None], X, U)
    key.data.foreach_set("co", X.astype(np.float32).ravel())
    for frame, value in ((1, 0.0), (frames, 1.0)):
        key.value = value
        key.keyframe_insert("value", frame=frame)
    return obj


def bind(method, mbi, model, U, T, frames):
    """Binds by the method; returns the seconds of the bind operator and of the operator with the model's
    first evaluation (Mesh Deform and Surface Deform bind in it; the add-on's shows the bound model)."""
    ctx = dict(object=model, active_object=model, selected_objects=[model])
    if method == "floor":
        bpy.app.handlers.frame_change_pre.append(lambda *_: model.data.update_tag())
        return 0.0, 0.0
    if method in ("mbi", "mbi-boundary"):
        faces = mbi.boundary_faces(U, T)
        moving = None
        if method == "mbi-boundary":  # what Mesh Deform sees: the interior follows by the harmonic extension
            moving = np.zeros(len(U), dtype=bool)
            moving[faces.ravel()] = True
        cage = cage_object("cage", U, faces, frames, moving)
        cage.data["mbi_tets"] = T.astype(np.int32).ravel().tolist()
        cage.mbi.is_cage = True
        bpy.context.scene.frame_set(1)
        start = time.perf_counter()
        with bpy.context.temp_override(active_object=cage, selected_objects=[model, cage]):
            bpy.ops.mbi.bind()
        operator = time.perf_counter() - start
        model.evaluated_get(bpy.context.evaluated_depsgraph_get())
        return operator, time.perf_counter() - start
    faces = mbi.boundary_faces(U, T)
    used = np.unique(faces)
    index = np.full(len(U), -1)
    index[used] = np.arange(len(used))
    nodes, faces = U[used], index[faces]
    if method == "surfacedeform":  # it refuses edges of more than two faces: those faces get their own vertices
        nodes, faces = unshared_crowded_edges(nodes, faces)
    cage = cage_object("cage", nodes, faces, frames)
    kind = "MESH_DEFORM" if method == "meshdeform" else "SURFACE_DEFORM"
    modifier = model.modifiers.new("deform", kind)
    if method == "meshdeform":
        modifier.object, modifier.precision = cage, 5
    else:
        modifier.target = cage
    bpy.context.scene.frame_set(1)  # the cage at rest (its key's value is the last keyframe's until then)
    start = time.perf_counter()
    with bpy.context.temp_override(**ctx):
        if method == "meshdeform":
            bpy.ops.object.meshdeform_bind(modifier="deform")
        else:
            bpy.ops.object.surfacedeform_bind(modifier="deform")
    model.evaluated_get(bpy.context.evaluated_depsgraph_get())  # the bind runs in the evaluation
    seconds = time.perf_counter() - start
    if not modifier.is_bound:
        raise RuntimeError("%s did not bind (the cage's boundary has %d edges shared by more than two "
                           "triangles)" % (kind, crowded_edges(index[faces])))
    return seconds, seconds


def edge_counts(faces):
    """Each face's three edges (f, 3, 2 sorted pairs), and per face edge how many faces share it."""
    edges = np.sort(np.stack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1), axis=2)
    _, inverse, counts = np.unique(edges.reshape(-1, 2), axis=0, return_inverse=True, return_counts=True)
    return counts[inverse.ravel()].reshape(-1, 3)


def crowded_edges(faces):
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int(np.sum(counts > 2))


def unshared_crowded_edges(nodes, faces):
    """The same surface with every face on an edge of more than two faces given its own copies of its
    three vertices (same positions, so the same motion): no edge is shared by more than two faces."""
    crowded = np.flatnonzero((edge_counts(faces) > 2).any(axis=1))
    faces = faces.copy()
    copies = nodes[faces[crowded]].reshape(-1, 3)
    faces[crowded] = len(nodes) + np.arange(len(copies)).reshape(-1, 3)
    return np.vstack([nodes, copies]), faces


def positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def dihedral_angles(X, faces, edges):
    N = np.cross(X[faces[:, 1]] - X[faces[:, 0]], X[faces[:, 2]] - X[faces[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True) + 1e-300
    cos = np.clip(np.einsum("ij,ij->i", N[edges[:, 0]], N[edges[:, 1]]), -1, 1)
    return np.degrees(np.arccos(cos))


def dihedral_change(model, rest, U, frames):
    """Mean and 99th percentile (degrees) of |dihedral - the analytic bend's| at the full bend."""
    bpy.context.scene.frame_set(frames)
    X = positions(model.evaluated_get(bpy.context.evaluated_depsgraph_get()).data)
    mesh = model.data
    mesh.calc_loop_triangles()
    faces = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int64)
    mesh.loop_triangles.foreach_get("vertices", faces)
    faces = faces.reshape(-1, 3)
    pairs = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    same = np.all(pairs[order][1:] == pairs[order][:-1], axis=1)
    face_of = order % len(faces)
    edges = np.stack([face_of[:-1][same], face_of[1:][same]], axis=1)  # faces sharing an edge
    change = np.abs(dihedral_angles(X, faces, edges) - dihedral_angles(bend(rest, 1.0, U), faces, edges))
    return float(change.mean()), float(np.percentile(change, 99))


def one(args):
    mbi = load_mbi()
    model = model_object(mbi, args.model_path, args.subdivide)
    c = mbi.read_control_mesh(args.cage)
    bpy.context.scene.frame_set(1)
    rest = positions(model.data)
    before = rss_mb()
    seconds, evaluated = bind(args.method, mbi, model, c.U, c.T, args.frames)
    times = []
    for _ in range(args.runs):
        for frame in range(1, args.frames + 1):
            start = time.perf_counter()
            bpy.context.scene.frame_set(frame)
            times.append(time.perf_counter() - start)
    result = dict(method=args.method, vertices=len(model.data.vertices), cage=len(c.U), bind_s=seconds,
                  bind_evaluated_s=evaluated,
                  frame_ms_median=1e3 * float(np.median(times)), frame_ms_min=1e3 * float(np.min(times)),
                  memory_mb=rss_mb() - before)
    if args.method != "floor" and len(model.data.vertices) <= 200000:
        result["dihedral_mean"], result["dihedral_p99"] = dihedral_change(model, rest, c.U, args.frames)
    print("RESULT " + json.dumps(result))


def run_one(args, method, subdivide, cage):
    command = [bpy.app.binary_path, "-b", "--factory-startup", "--python", os.path.abspath(__file__), "--",
               "--one", method, "--model-path", args.model_path, "--subdivide", str(subdivide), "--cage", cage,
               "--frames", str(args.frames), "--runs", str(args.runs)]
    try:
        run = subprocess.run(command, capture_output=True, text=True, timeout=args.limit)
    except subprocess.TimeoutExpired:
        return dict(method=method, skipped="over %d s" % args.limit)
    for line in run.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    errors = [line for line in (run.stdout + run.stderr).splitlines() if "Error" in line]
    return dict(method=method, skipped="failed: " + (errors[-1] if errors else (run.stdout + run.stderr)[-300:]))


def median_of(results):
    """One result from the same run in several processes: each figure's median (Blender's own
    resident set varies by some MB from process to process)."""
    done = [r for r in results if "skipped" not in r]
    if len(done) < len(results):
        return next(r for r in results if "skipped" in r)
    merged = dict(done[0], processes=len(done))
    for key, value in done[0].items():
        if isinstance(value, float):
            merged[key] = float(np.median([r[key] for r in done]))
    return merged


def main(argv):
    parser = argparse.ArgumentParser(prog="side_by_side.py")
    parser.add_argument("--model", default="stanford-bunny")
    parser.add_argument("--model-path", default="")
    parser.add_argument("--subdivide", type=int, nargs="+", default=[0, 2])
    parser.add_argument("--vertices", type=int, default=1000)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--limit", type=int, default=300)
    parser.add_argument("--processes", type=int, default=1)
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--one", choices=METHODS)
    parser.add_argument("--cage", default="")
    args = parser.parse_args(argv)
    if not args.model_path:
        args.model_path = os.path.join(os.environ.get("MBI_MODELS_DIR", "."), args.model + ".obj")
    if args.one:
        args.method = args.one
        args.subdivide = args.subdivide[0]
        return one(args)
    mbi = load_mbi()
    V, F = mbi.read_surface(args.model_path)
    cage = mbi.cage(V, F, vertices=args.vertices)
    folder = tempfile.mkdtemp(prefix="mbi-side-by-side-")
    base = os.path.join(folder, "cage")
    mbi.write_tetgen(base, cage.U, cage.T)
    rows = []
    for subdivide in args.subdivide:
        for method in args.methods:
            result = median_of([run_one(args, method, subdivide, base) for _ in range(args.processes)])
            result.update(model=args.model, subdivide=subdivide)
            print(json.dumps(result), flush=True)
            rows.append(result)
    print("\n| model | vertices | method | bind (s): operator / with first evaluation | per frame median / min (ms) "
          "| memory added (MB) "
          "| dihedral change mean / p99 (deg) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        if "skipped" in r:
            print("| %s x%d | | %s | skipped: %s | | |" % (r["model"], r["subdivide"], r["method"], r["skipped"][:80]))
        else:
            quality = "%.3f / %.2f" % (r["dihedral_mean"], r["dihedral_p99"]) if "dihedral_mean" in r else ""
            print("| %s x%d | %d | %s | %.3f / %.3f | %.2f / %.2f | %.0f | %s |" % (
                r["model"], r["subdivide"], r["vertices"], r["method"], r["bind_s"], r["bind_evaluated_s"],
                r["frame_ms_median"],
                r["frame_ms_min"], r["memory_mb"], quality))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    sys.exit(0)
