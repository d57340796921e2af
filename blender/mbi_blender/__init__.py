"""mbi in Blender: a tetrahedral cage around a mesh, bound meshes that follow the cage's animation.

The cage is a mesh object whose vertices are the control nodes (animate them with Blender's own
tools) and whose tetrahedra are stored in its mesh data; a bound mesh follows through a point
attribute that a frame-change handler writes and a Geometry Nodes modifier applies (docs/blender.md).
"""

bl_info = {
    "name": "mbi deformation",
    "author": "mbi",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > mbi",
    "description": "Cage, bind and deform dense meshes with modified barycentric interpolation",
    "category": "Animation",
}

from . import bake, bind_op, cage_op, import_op, live, panel, physics, preferences, settings, table_op  # noqa: E402

_modules = (preferences, settings, cage_op, import_op, bind_op, bake, physics, table_op, panel, live)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()
