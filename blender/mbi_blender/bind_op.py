"""Bind: the selected meshes to the active cage (embedding and precompute, kept by the live path)."""
import bpy

from . import live, module, settings


class MBI_OT_bind(bpy.types.Operator):
    """Bind the selected meshes to the active mbi cage"""
    bl_idname = "mbi.bind"
    bl_label = "Bind to mbi cage"
    bl_options = {"REGISTER", "UNDO"}

    method: bpy.props.EnumProperty(name="Method", items=settings.METHODS, default="modified-bi")
    alpha: bpy.props.FloatProperty(name="Alpha", default=0.0, min=0.0,
                                   description="Weight of modified-BI's E_vibr (0: the default, 0.1)")

    def execute(self, context):
        cage = context.active_object
        if cage is None or not cage.mbi.is_cage:
            self.report({"ERROR"}, "mbi bind: make the mbi cage the active object")
            return {"CANCELLED"}
        models = [o for o in context.selected_objects if o.type == "MESH" and o is not cage]
        if not models:
            self.report({"ERROR"}, "mbi bind: select the meshes to bind, then the cage")
            return {"CANCELLED"}
        context.view_layer.update()  # world matrices of transforms set by a script
        depsgraph = context.evaluated_depsgraph_get()  # the cage as evaluated, before the bind tags anything
        try:
            module.load()
            for model in models:
                seconds = live.bind(model, cage, self.method, self.alpha, depsgraph)
                self.report({"INFO"}, "mbi bind: %s, %d points in %.3f s"
                            % (model.name, len(model.data.vertices), seconds))
        except (RuntimeError, ValueError) as error:
            self.report({"ERROR"}, "mbi bind: %s" % error)
            return {"CANCELLED"}
        return {"FINISHED"}


class MBI_OT_unbind(bpy.types.Operator):
    """Unbind the selected meshes: remove their mbi modifier and attribute"""
    bl_idname = "mbi.unbind"
    bl_label = "Unbind from mbi cage"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        for model in context.selected_objects:
            if model.type == "MESH" and model.mbi.cage is not None:
                live.unbind(model)
        return {"FINISHED"}


def register():
    bpy.utils.register_class(MBI_OT_bind)
    bpy.utils.register_class(MBI_OT_unbind)


def unregister():
    bpy.utils.unregister_class(MBI_OT_unbind)
    bpy.utils.unregister_class(MBI_OT_bind)
