"""The sidebar panel: cage, bind, and the state of the selected object."""
import bpy

from . import binding, live, table_op


class MBI_PT_panel(bpy.types.Panel):
    bl_label = "mbi"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "mbi"

    def draw(self, context):
        layout = self.layout
        layout.operator("mbi.cage")
        layout.operator("mbi.import_cage")
        layout.operator("mbi.bind")
        layout.operator("mbi.unbind")
        row = layout.row()
        row.operator("mbi.bake", text="Bake")
        row.operator("mbi.unbake", text="Un-bake")
        obj = context.active_object
        if obj is None:
            return
        if obj.mbi.is_cage:
            layout.label(text="Cage: %d nodes" % len(obj.data.vertices))
            layout.prop(obj.mbi, "interior")
            box = layout.box()
            box.label(text="Physics (mbi FEM)")
            for name in ("young", "poisson", "density", "mass_damping", "stiffness_damping", "substeps"):
                box.prop(obj.mbi, name)
            box.prop_search(obj.mbi, "pin_group", obj, "vertex_groups")
            box.prop(obj.mbi, "pin_motion")
            if obj.mbi.pin_motion == "rigid":
                for name in ("pin_velocity", "pin_rate", "pin_axis", "pin_center", "pin_start", "pin_stop"):
                    box.prop(obj.mbi, name)
            elif obj.mbi.pin_motion == "object":
                box.prop(obj.mbi, "pin_object")
                target = obj.mbi.pin_object
                if target is not None and target.type == "ARMATURE":
                    box.prop_search(obj.mbi, "pin_bone", target.pose, "bones")
            box.prop(obj.mbi, "contact_stiffness")
            box.operator("mbi.simulate")
        elif obj.mbi.cage is not None:
            layout.label(text="Bound to %s" % obj.mbi.cage.name)
            layout.label(text="Method: %s" % obj.mbi.method)
            layout.label(text="Bind: %.3f s for %d points" % (obj.mbi.bind_seconds, len(obj.data.vertices)))
            if obj.name in binding.notes:
                layout.label(text=binding.notes[obj.name], icon="INFO")
            _table(layout, obj)
            if obj.mbi.baked and live.CACHE_MODIFIER in obj.modifiers:
                layout.label(text="Baked: %s" % obj.modifiers[live.CACHE_MODIFIER].filepath)
            if obj.name in live.errors:
                layout.label(text=live.errors[obj.name], icon="ERROR")
        if not obj.mbi.is_cage and obj.mbi.cage is None:
            box = layout.box()
            box.prop(obj.mbi, "collider")
            if obj.mbi.collider != "none":
                box.prop(obj.mbi, "friction")


def _table(layout, model):
    layout.operator("mbi.discontinuity")
    if model.name not in table_op.tables:
        return
    frame, rows, faces, seconds = table_op.tables[model.name]
    box = layout.box()
    box.label(text="Frame %d, %d faces, %.3f s" % (frame, faces, seconds))
    box.label(text="jump: mean / std / max")
    for label, mean, std, largest in rows:
        box.label(text="%s: %.2g / %.2g / %.2g" % (label, mean, std, largest))


def register():
    bpy.utils.register_class(MBI_PT_panel)


def unregister():
    bpy.utils.unregister_class(MBI_PT_panel)
