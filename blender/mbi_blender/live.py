"""The live path: the evaluated cage's nodes deform the bound meshes into their "mbi" shape key.

On each frame change, and when a cage is edited in place, a handler reads the cage as Blender
evaluated it (armature, shape keys, hooks, lattice), runs the bound Deformer (float32 kernel, no
allocation) and writes the positions into the model's shape key "mbi" (value 1, relative to the
basis), so the mesh data's basis stays the rest shape. The Deformers are not saved: they are
rebuilt from the .blend's data on first use after a file load, an undo or a change of the bind
(docs/blender.md).
"""
import bpy
import numpy as np
from bpy.app.handlers import persistent

from . import harmonic, module, storage

SHAPE_KEY = "mbi"
CACHE_MODIFIER = "mbi cache"  # the Mesh Cache modifier of a baked model
OUTSIDE_TOLERANCE = 1e-4  # of the model's size: points farther outside the cage are refused (mbi's check)
_bound = {}   # model.name_full -> _Binding
errors = {}   # model name -> last message of the live path (shown in the panel)
_extensions = {}  # cage.name_full -> (rest key, harmonic.Extension)


class _Binding:
    def __init__(self, key, deformer, inverse):
        self.key = key
        self.deformer = deformer
        self.inverse = inverse  # cage space to the model's space, None when the identity
        self.out = np.empty((deformer.points, 3), dtype=np.float32)


def _key(model, cage, tets):
    s = model.mbi
    return (cage.name_full, len(cage.data.vertices), len(tets), len(model.data.vertices), s.method, s.alpha,
            tuple(s.bind_matrix))


def _matrix(flat):
    return np.array(flat, dtype=np.float64).reshape(4, 4)


def _build(model, cage):
    mbi = module.load()
    tets = storage.tets(cage.data)
    if tets is None:
        raise ValueError("%s holds no tetrahedra (not an mbi cage)" % cage.name)
    s = model.mbi
    B = _matrix(s.bind_matrix)
    P = storage.positions(model.data).astype(np.float64) @ B[:3, :3].T + B[:3, 3]
    U = storage.positions(cage.data).astype(np.float64)
    alpha = s.alpha if s.alpha > 0 else None
    try:
        deformer = mbi.Deformer(U, tets, P, method=s.method, alpha=alpha, max_outside=OUTSIDE_TOLERANCE)
    except mbi.Error as error:
        raise ValueError("%s does not fit in the cage %s: %s" % (model.name, cage.name, error)) from error
    inverse = None if np.allclose(B, np.eye(4), rtol=0, atol=0) else np.linalg.inv(B)
    return _Binding(_key(model, cage, tets), deformer, inverse)


def _binding(model):
    """The model's Deformer, rebuilt when missing or when its cage, mesh or options changed."""
    cage = model.mbi.cage
    entry = _bound.get(model.name_full)
    tets_count = len(cage.data.get(storage.TETS_KEY, [])) // 4
    if entry is None or entry.key != _key(model, cage, range(tets_count)):
        entry = _bound[model.name_full] = _build(model, cage)
    return entry


def _extension(cage, tets_count):
    """The cage's harmonic extension, built again when its rest nodes changed."""
    U = storage.positions(cage.data).astype(np.float64)
    key = (tets_count, U.tobytes())
    entry = _extensions.get(cage.name_full)
    if entry is None or entry[0] != key:
        tets = storage.tets(cage.data)
        entry = _extensions[cage.name_full] = (key, harmonic.Extension(U, tets, module.load().boundary_faces(U, tets)))
    return entry[1]


def cage_nodes(cage, depsgraph):
    """The cage's nodes as evaluated, the interior ones moved with the boundary per the cage's setting."""
    data = cage.evaluated_get(depsgraph).data
    X = storage.positions(data)
    tets_count = len(cage.data.get(storage.TETS_KEY, [])) // 4
    if len(X) != len(cage.data.vertices):
        raise ValueError("the evaluated cage %s has %d vertices, its mesh %d: a modifier changed its topology"
                         % (cage.name, len(X), len(cage.data.vertices)))
    mode = cage.mbi.interior
    if mode == "animated" or tets_count == 0:
        return X.astype(np.float64)
    extension = _extension(cage, tets_count)
    if mode == "harmonic" or extension.boundary_moved_only(X):
        return extension.apply(X)
    return X.astype(np.float64)


def shape_key(model):
    if model.data.shape_keys is None:
        model.shape_key_add(name="Basis", from_mix=False)
    keys = model.data.shape_keys.key_blocks
    block = keys.get(SHAPE_KEY) or model.shape_key_add(name=SHAPE_KEY, from_mix=False)
    block.value = 1.0
    return block


def bind(model, cage, method, alpha):
    """Binds the model to the cage now; returns the seconds the embedding and precompute took.

    A refused bind (the cage does not enclose the model, mbi refused the data) leaves the model's
    earlier binding as it was."""
    import time
    s = model.mbi
    earlier = (s.cage, s.method, s.alpha, tuple(s.bind_matrix))
    B = np.array(cage.matrix_world.inverted() @ model.matrix_world)
    s.cage, s.method, s.alpha, s.bind_matrix = cage, method, alpha, B.ravel().tolist()
    start = time.perf_counter()
    _bound.pop(model.name_full, None)
    try:
        _binding(model)
    except (RuntimeError, ValueError):
        _bound.pop(model.name_full, None)
        s.cage, s.method, s.alpha, s.bind_matrix = earlier
        raise
    seconds = time.perf_counter() - start
    shape_key(model)
    return seconds


def shape_positions(model):
    """(p, 3) float32: the model's live positions (its shape key, in the model's space)."""
    block = shape_key(model)
    co = np.empty(len(block.data) * 3, dtype=np.float32)
    block.data.foreach_get("co", co)
    return co.reshape(-1, 3)


def unbind(model):
    _bound.pop(model.name_full, None)
    if CACHE_MODIFIER in model.modifiers:
        model.modifiers.remove(model.modifiers[CACHE_MODIFIER])
    model.mbi.baked = False
    keys = model.data.shape_keys
    if keys is not None and SHAPE_KEY in keys.key_blocks:
        model.shape_key_remove(keys.key_blocks[SHAPE_KEY])
    model.mbi.cage = None


def deform(model, depsgraph):
    """Writes the model's positions for the cage as evaluated in depsgraph into its shape key."""
    entry = _binding(model)
    X = cage_nodes(model.mbi.cage, depsgraph)
    out = entry.deformer.deform(X, out=entry.out)
    if entry.inverse is not None:
        inv = entry.inverse
        out = (out @ inv[:3, :3].T + inv[:3, 3]).astype(np.float32)
    block = shape_key(model)
    block.data.foreach_set("co", out.ravel())
    model.data.update()


def update_all(depsgraph, cages=None):
    """Deforms every bound model, or those bound to the cages named in cages."""
    for model in bpy.data.objects:
        if model.type != "MESH" or model.mbi.cage is None or model.mbi.baked:
            continue
        if cages is not None and model.mbi.cage.name_full not in cages:
            continue
        errors.pop(model.name, None)
        try:
            deform(model, depsgraph)
        except (RuntimeError, ValueError) as error:
            errors[model.name] = str(error)
            print("mbi: %s: %s" % (model.name, error))


@persistent
def _on_frame(scene, depsgraph=None):
    update_all(depsgraph or bpy.context.evaluated_depsgraph_get())


@persistent
def _on_depsgraph(scene, depsgraph):
    """A cage edited without a frame change (edit mode, a posed armature, a key's value)."""
    cages = {u.id.original.name_full for u in depsgraph.updates
             if isinstance(u.id, bpy.types.Object) and u.is_updated_geometry and u.id.mbi.is_cage}
    if cages:  # the models written here are no cages: no second round
        update_all(depsgraph, cages)


@persistent
def _on_load(*_):
    _bound.clear()
    _extensions.clear()
    errors.clear()
    update_all(bpy.context.evaluated_depsgraph_get())


@persistent
def _on_undo(*_):
    update_all(bpy.context.evaluated_depsgraph_get())


_HANDLERS = ((bpy.app.handlers.frame_change_post, _on_frame),
             (bpy.app.handlers.depsgraph_update_post, _on_depsgraph), (bpy.app.handlers.load_post, _on_load),
             (bpy.app.handlers.undo_post, _on_undo), (bpy.app.handlers.redo_post, _on_undo))


def register():
    for handlers, function in _HANDLERS:
        if function not in handlers:
            handlers.append(function)


def unregister():
    for handlers, function in _HANDLERS:
        if function in handlers:
            handlers.remove(function)
    _bound.clear()
    _extensions.clear()
