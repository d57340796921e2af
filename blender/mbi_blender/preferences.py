"""The add-on's preference: where the mbi module is, for a Blender that does not find it alone."""
import bpy


class MbiPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    module_dir: bpy.props.StringProperty(
        name="mbi module folder", subtype="DIR_PATH",
        description="Folder holding the Python package mbi (e.g. <mbi build>/python); empty: Blender's own path")

    def draw(self, context):
        self.layout.prop(self, "module_dir")


def register():
    bpy.utils.register_class(MbiPreferences)


def unregister():
    bpy.utils.unregister_class(MbiPreferences)
