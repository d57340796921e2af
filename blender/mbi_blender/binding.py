"""Bindings: each bound model's Deformer, built from the .blend's data, kept in memory, never stale.

A Deformer is rebuilt when its inputs changed: the cage, the vertex counts, method, alpha or the
bind matrix (compared every frame), the cage's rest nodes (compared every frame: a few thousand
floats), or the rest content (a hash of the cage's rest nodes and tetrahedra, the model's rest
vertices and the bind matrix), stored in the .blend at bind and checked after a file load, an
undo or redo, and an edit of the model's mesh. A rebuild for a changed rest is noted in the panel.
"""
import hashlib
import time

import numpy as np

from . import module, storage

OUTSIDE_TOLERANCE = 1e-4  # of the model's size: points farther outside the cage are refused (mbi's check)
_bound = {}  # model.name_full -> Binding
notes = {}   # model name -> a note on its binding for the panel


class Binding:
    def __init__(self, key, deformer, inverse, content, cage_rest, seconds):
        self.key = key
        self.deformer = deformer
        self.inverse = inverse  # cage space to the model's space, None when the identity
        self.content = content  # rest_hash at build
        self.cage_rest = cage_rest  # the cage's rest nodes (bytes) at build
        self.seconds = seconds  # embedding and precompute
        self.out = np.empty((deformer.points, 3), dtype=np.float32)


def _key(model, cage, tets_count):
    s = model.mbi
    return (cage.name_full, len(cage.data.vertices), tets_count, len(model.data.vertices), s.method, s.alpha,
            tuple(s.bind_matrix))


def _tets_count(cage):
    return len(cage.data.get(storage.TETS_KEY, [])) // 4


def rest_hash(model, cage, U32=None, tets=None, rest=None):
    """Hex digest of what a bind depends on besides its options: rest nodes, tetrahedra, rest model, matrix
    (the arrays when the caller has them read already)."""
    h = hashlib.sha1(usedforsecurity=False)  # a fast digest: detects edits, guards nothing
    h.update((storage.positions(cage.data) if U32 is None else U32).tobytes())
    h.update(np.asarray(cage.data.get(storage.TETS_KEY, []) if tets is None else tets, dtype=np.int32).tobytes())
    h.update((storage.positions(model.data) if rest is None else rest).tobytes())
    h.update(np.asarray(model.mbi.bind_matrix, dtype=np.float64).tobytes())
    return h.hexdigest()


def _build(model, cage):
    mbi = module.load()
    tets = storage.tets(cage.data)
    if tets is None:
        raise ValueError("%s holds no tetrahedra (not an mbi cage)" % cage.name)
    s = model.mbi
    B = np.array(s.bind_matrix, dtype=np.float64).reshape(4, 4)
    rest = storage.positions(model.data)
    identity = np.array_equal(B, np.eye(4))
    # float32 as Blender stores it when the model is in cage space (mbi reads it into float64 once)
    P = rest if identity else rest.astype(np.float64) @ B[:3, :3].T + B[:3, 3]
    U32 = storage.positions(cage.data)
    alpha = s.alpha if s.alpha > 0 else None
    start = time.perf_counter()
    try:
        deformer = mbi.Deformer(U32.astype(np.float64), tets, P, method=s.method, alpha=alpha,
                                max_outside=OUTSIDE_TOLERANCE)
    except mbi.Error as error:
        raise ValueError("%s does not fit in the cage %s: %s" % (model.name, cage.name, error)) from error
    seconds = time.perf_counter() - start
    content = rest_hash(model, cage, U32, tets, rest)
    if s.rest_hash and s.rest_hash != content and len(s.rest_hash) == len(content):  # not an older digest
        notes[model.name] = "rest shape changed since the bind: bound again (%.3f s)" % seconds
    s.rest_hash, s.bind_seconds = content, seconds
    return Binding(_key(model, cage, len(tets)), deformer, None if identity else np.linalg.inv(B), content,
                   U32.tobytes(), seconds)


def get(model):
    """The model's Binding, rebuilt when missing or when its cage, counts, options or cage's rest changed."""
    cage = model.mbi.cage
    entry = _bound.get(model.name_full)
    if (entry is None or entry.key != _key(model, cage, _tets_count(cage))
            or entry.cage_rest != storage.positions(cage.data).tobytes()):
        entry = _bound[model.name_full] = _build(model, cage)
    return entry


def check_content(model):
    """Drops the model's Binding when the rest content differs from the one it was built from."""
    entry = _bound.get(model.name_full)
    if entry is not None and entry.content != rest_hash(model, model.mbi.cage):
        del _bound[model.name_full]


def bind(model, cage, method, alpha, matrix):
    """Binds now; returns the seconds of the embedding and precompute. A refused bind (the cage does not
    enclose the model, mbi refused the data) leaves the earlier binding as it was."""
    s = model.mbi
    earlier = (s.cage, s.method, s.alpha, tuple(s.bind_matrix), s.rest_hash)
    s.cage, s.method, s.alpha, s.bind_matrix, s.rest_hash = cage, method, alpha, matrix, ""
    _bound.pop(model.name_full, None)
    notes.pop(model.name, None)
    try:
        return get(model).seconds
    except (RuntimeError, ValueError):
        _bound.pop(model.name_full, None)
        s.cage, s.method, s.alpha, s.bind_matrix, s.rest_hash = earlier
        raise


def forget(model):
    _bound.pop(model.name_full, None)
    notes.pop(model.name, None)


def clear():
    _bound.clear()
    notes.clear()
