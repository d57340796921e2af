"""The discontinuity table (the paper's Table 2) of a bound model's cage at the current frame."""
import time

import bpy
import numpy as np

from . import live, module, storage

tables = {}  # model name -> (frame, rows [(label, mean, std, max)], faces, seconds), shown in the panel


def discontinuity(model, depsgraph, frame):
    """BI, modified-BI and Phong jumps of the deformation gradient over the cage's interior faces."""
    mbi = module.load()
    cage = model.mbi.cage
    U = storage.positions(cage.data).astype(np.float64)
    T = storage.tets(cage.data)
    X = live.cage_nodes(cage, depsgraph)
    start = time.perf_counter()
    solver = mbi.ModifiedBI(U, T, alpha=model.mbi.alpha if model.mbi.alpha > 0 else None)
    table = mbi.discontinuity_table(solver, X, solver.solve(X), mbi.Phong(U, T).M(X))
    rows = [(label, s.mean, s.std, s.max) for label, s in
            (("BI", table.bi), ("mod-BI", table.modified_bi), ("Phong", table.phong),
             ("BI/mod-BI", table.ratio), ("BI/Phong", table.phong_ratio)) if s is not None]
    tables[model.name] = (frame, rows, table.faces, time.perf_counter() - start)
    return tables[model.name]


class MBI_OT_discontinuity(bpy.types.Operator):
    """Compute the discontinuity table of the active bound mesh's cage at this frame"""
    bl_idname = "mbi.discontinuity"
    bl_label = "Discontinuity at this frame"

    def execute(self, context):
        model = context.active_object
        if model is None or model.mbi.cage is None:
            self.report({"ERROR"}, "mbi discontinuity: make a bound mesh the active object")
            return {"CANCELLED"}
        try:
            discontinuity(model, context.evaluated_depsgraph_get(), context.scene.frame_current)
        except (RuntimeError, ValueError) as error:
            self.report({"ERROR"}, "mbi discontinuity: %s" % error)
            return {"CANCELLED"}
        return {"FINISHED"}


def register():
    bpy.utils.register_class(MBI_OT_discontinuity)


def unregister():
    bpy.utils.unregister_class(MBI_OT_discontinuity)
