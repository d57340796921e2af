"""Import: a tetrahedral mesh the user brings (TetGen .node/.ele, Gmsh .msh, .vtk, .vtu) as an mbi cage."""
import os

import bpy
from bpy_extras.io_utils import ImportHelper

from . import cage_op, module


def import_cage(context, path):
    """The control mesh in the file as a new cage object (file coordinates = world space)."""
    mbi = module.load()
    mesh = mbi.read_control_mesh(path)  # mbi.FileError / mbi.Error name the file and line
    if mesh.dim != 3:
        raise ValueError("%s: a %dD mesh; a cage needs tetrahedra" % (path, mesh.dim))
    name = os.path.splitext(os.path.basename(path))[0] + " cage"
    return cage_op.new_cage_object(context, mbi, name, mesh.U, mesh.T), mesh


class MBI_OT_import_cage(bpy.types.Operator, ImportHelper):
    """Import a tetrahedral mesh (.node/.ele, .msh, .vtk, .vtu) as an mbi cage"""
    bl_idname = "mbi.import_cage"
    bl_label = "Import tet mesh as mbi cage"
    bl_options = {"REGISTER", "UNDO"}

    filter_glob: bpy.props.StringProperty(default="*.node;*.ele;*.msh;*.vtk;*.vtu", options={"HIDDEN"})

    def execute(self, context):
        try:
            obj, mesh = import_cage(context, self.filepath)
        except (RuntimeError, ValueError) as error:  # mbi.Error is a ValueError
            self.report({"ERROR"}, "mbi import: %s" % error)
            return {"CANCELLED"}
        for note in mesh.notes:
            self.report({"WARNING"}, "mbi import: %s" % note)
        self.report({"INFO"}, "mbi import: %s, %d nodes, %d tetrahedra" % (obj.name, len(mesh.U), len(mesh.T)))
        return {"FINISHED"}


def _menu(self, context):
    self.layout.operator(MBI_OT_import_cage.bl_idname, text="mbi cage (.node, .msh, .vtk, .vtu)")


def register():
    bpy.utils.register_class(MBI_OT_import_cage)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    bpy.utils.unregister_class(MBI_OT_import_cage)
