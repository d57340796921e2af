"""Cage: a tetrahedral control mesh made by mbi.cage around the selected meshes, as a new object."""
import bpy
import numpy as np

from . import module, storage


def world_surface(objects):
    """Vertices (world space, float64) and triangles of the meshes, one surface."""
    V, F, offset = [], [], 0
    for obj in objects:
        mesh = obj.data
        local = storage.positions(mesh).astype(np.float64)
        M = np.array(obj.matrix_world)
        V.append(local @ M[:3, :3].T + M[:3, 3])
        F.append(storage.triangles(mesh) + offset)
        offset += len(mesh.vertices)
    return np.concatenate(V), np.concatenate(F)


def make_cage(context, mbi, objects, vertices, mesher):
    V, F = world_surface(objects)
    if len(F) == 0:
        raise ValueError("%s has no faces: mbi needs a closed surface to cage"
                         % ", ".join(o.name for o in objects))
    cage = mbi.cage(V, F, vertices=vertices, mesher=mesher)
    return new_cage_object(context, mbi, objects[0].name + " cage", cage.U, cage.T), cage


def new_cage_object(context, mbi, name, U, T):
    """A wire object holding the control mesh (U, T), linked, selected and active: ready to bind."""
    mesh = bpy.data.meshes.new(name)
    storage.fill_cage_mesh(mesh, U, T, mbi.boundary_faces(U, T))
    obj = bpy.data.objects.new(mesh.name, mesh)
    obj.mbi.is_cage = True
    obj.display_type = "WIRE"
    context.collection.objects.link(obj)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    return obj


class MBI_OT_cage(bpy.types.Operator):
    """Make a tetrahedral cage around the selected meshes"""
    bl_idname = "mbi.cage"
    bl_label = "Make mbi cage"
    bl_options = {"REGISTER", "UNDO"}

    vertices: bpy.props.IntProperty(name="Vertices", default=200, min=3,
                                    description="Target number of control nodes")
    mesher: bpy.props.EnumProperty(name="Mesher", items=[("voxel", "Voxel", ""), ("tetgen", "TetGen", "")])

    def execute(self, context):
        objects = [o for o in context.selected_objects if o.type == "MESH" and not o.mbi.is_cage]
        if not objects:
            self.report({"ERROR"}, "mbi cage: select a mesh object to cage")
            return {"CANCELLED"}
        context.view_layer.update()  # world matrices of transforms set by a script
        try:
            mbi = module.load()
            obj, cage = make_cage(context, mbi, objects, self.vertices, self.mesher)
        except (RuntimeError, ValueError) as error:  # mbi.Error is a ValueError
            self.report({"ERROR"}, "mbi cage: %s" % error)
            return {"CANCELLED"}
        self.report({"INFO"}, "mbi cage: %d nodes, %d tetrahedra in %.3f s"
                    % (len(cage.U), len(cage.T), cage.seconds))
        return {"FINISHED"}


def register():
    bpy.utils.register_class(MBI_OT_cage)


def unregister():
    bpy.utils.unregister_class(MBI_OT_cage)
