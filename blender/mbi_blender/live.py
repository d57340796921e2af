"""The live path: the evaluated cage's nodes deform the bound meshes through a point attribute.

On each frame change, and when a cage is edited in place, a handler reads the cage as Blender
evaluated it (armature, shape keys, hooks, lattice), runs the bound Deformer (float32 kernel, no
allocation) and writes the positions into the model's point attribute "mbi_position", which the
add-on's Geometry Nodes modifier "mbi" (first in the stack) sets as the positions: the mesh's
vertices stay the rest shape, and an attribute takes a fast write (a shape key has none in 3.4).
The Deformers are not saved: they are rebuilt from the .blend's data when stale (binding.py,
docs/blender.md).
"""
import contextlib

import bpy
import numpy as np
from bpy.app.handlers import persistent

from . import binding, gn, harmonic, module, storage

CACHE_MODIFIER = "mbi cache"  # the Mesh Cache modifier of a baked model
errors = {}   # model name -> last message of the live path (shown in the panel)
_extensions = {}  # cage.name_full -> (rest key, harmonic.Extension)
_just_bound = set()  # models the bind operator wrote: the next depsgraph update is that write, not an edit
_paused = []  # non-empty: the handlers do nothing (frames stepped only to read animated transforms)


@contextlib.contextmanager
def paused():
    _paused.append(True)
    try:
        yield
    finally:
        _paused.pop()


def _extension(cage, tets_count):
    """The cage's harmonic extension, built again when its rest nodes changed."""
    U = storage.positions(cage.data).astype(np.float64)
    key = (tets_count, U.tobytes())
    entry = _extensions.get(cage.name_full)
    if entry is None or entry[0] != key:
        tets = storage.tets(cage.data)
        entry = _extensions[cage.name_full] = (key, harmonic.Extension(U, tets))
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
    if mode == "animated" or tets_count == 0 or (mode == "auto" and np.array_equal(X, storage.positions(cage.data))):
        return X.astype(np.float64)  # at rest the extension is the identity: not built for it
    extension = _extension(cage, tets_count)
    if mode == "harmonic" or extension.boundary_moved_only(X):
        return extension.apply(X)
    return X.astype(np.float64)


def bind(model, cage, method, alpha, depsgraph):
    """Binds the model to the cage now and writes its positions for the cage as evaluated in depsgraph (taken
    before the bind changed anything, so no evaluation runs here); returns the seconds of the embedding and
    precompute."""
    matrix = np.array(cage.matrix_world.inverted() @ model.matrix_world).ravel().tolist()
    seconds = binding.bind(model, cage, method, alpha, matrix)
    deform(model, depsgraph)
    _just_bound.add(model.name_full)
    return seconds


def live_positions(model):
    """(p, 3) float32: the model's live positions (its attribute, in the model's space)."""
    attribute = gn.attribute(model)[0]
    co = np.empty(len(attribute.data) * 3, dtype=np.float32)
    attribute.data.foreach_get("vector", co)
    return co.reshape(-1, 3)


def unbind(model):
    binding.forget(model)
    if CACHE_MODIFIER in model.modifiers:
        model.modifiers.remove(model.modifiers[CACHE_MODIFIER])
    model.mbi.baked = False
    gn.remove(model)
    model.mbi.cage = None


def deform(model, depsgraph):
    """Writes the model's positions for the cage as evaluated in depsgraph into its attribute."""
    entry = binding.get(model)
    X = cage_nodes(model.mbi.cage, depsgraph)
    out = entry.deformer.deform(X, out=entry.out)
    if entry.inverse is not None:
        inv = entry.inverse
        out = (out @ inv[:3, :3].T + inv[:3, 3]).astype(np.float32)
    gn.write(model, out)
    gn.modifier(model)
    model.data.update()


def bound_models():
    return [o for o in bpy.data.objects if o.type == "MESH" and o.mbi.cage is not None and not o.mbi.baked]


def update_all(depsgraph, cages=None, models=()):
    """Deforms every bound model, or those bound to the cages named in cages and those named in models."""
    for model in bound_models():
        if cages is not None and model.mbi.cage.name_full not in cages and model.name_full not in models:
            continue
        errors.pop(model.name, None)
        try:
            deform(model, depsgraph)
        except (RuntimeError, ValueError) as error:
            errors[model.name] = str(error)
            print("mbi: %s: %s" % (model.name, error))


@persistent
def _on_frame(scene, depsgraph=None):
    if _paused:
        return
    _just_bound.clear()
    update_all(depsgraph or bpy.context.evaluated_depsgraph_get())


@persistent
def _on_depsgraph(scene, depsgraph):
    """A cage edited without a frame change (edit mode, a posed armature, a key's value), or a bound
    model's mesh edited: its rest content is checked (a hash; frame changes do not come here)."""
    if _paused:
        return
    cages, models = set(), set()
    for update in depsgraph.updates:
        obj = update.id.original if isinstance(update.id, bpy.types.Object) else None
        if obj is None or not update.is_updated_geometry:
            continue
        if obj.mbi.is_cage:
            cages.add(obj.name_full)
        elif obj.type == "MESH" and obj.mbi.cage is not None and obj.name_full not in _just_bound:
            binding.check_content(obj)
            models.add(obj.name_full)
    _just_bound.clear()
    if cages or models:
        update_all(depsgraph, cages, models)


@persistent
def _on_load(*_):
    _just_bound.clear()
    binding.clear()
    _extensions.clear()
    errors.clear()
    update_all(bpy.context.evaluated_depsgraph_get())


@persistent
def _on_undo(*_):
    for model in bound_models():
        binding.check_content(model)
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
    binding.clear()
    _extensions.clear()
