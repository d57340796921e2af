"""The live path's carrier: a point attribute "mbi_position" on the model's mesh, set as the positions
by a Geometry Nodes modifier "mbi" (Named Attribute -> Set Position) that the add-on creates, first
in the stack, and removes at unbind with its node group when no other model uses it.
"""
import bpy

from . import storage

ATTRIBUTE = "mbi_position"
MODIFIER = "mbi"
GROUP = "mbi live"
OWNER_KEY = "mbi_live"  # ID property marking the node groups the add-on made


def attribute(model, initial=None):
    """The model's live attribute; a new one starts at initial ((p, 3) float32) or the rest positions
    (never zeros on screen). Returns (attribute, whether it is new)."""
    mesh = model.data
    found = mesh.attributes.get(ATTRIBUTE)
    if found is not None and found.data_type == "FLOAT_VECTOR" and found.domain == "POINT":
        return found, False
    if found is not None:
        mesh.attributes.remove(found)
    made = mesh.attributes.new(ATTRIBUTE, "FLOAT_VECTOR", "POINT")
    made = mesh.attributes[ATTRIBUTE]  # the reference from new() goes stale when the layers move
    made.data.foreach_set("vector", (storage.positions(mesh) if initial is None else initial).ravel())
    return made, True


def write(model, positions):
    """The model's positions ((p, 3) float32) into its attribute, written once."""
    found, new = attribute(model, positions)
    if not new:
        found.data.foreach_set("vector", positions.ravel())


def node_group():
    """The add-on's node group: the geometry with its positions taken from the attribute."""
    for group in bpy.data.node_groups:
        if group.get(OWNER_KEY) and group.bl_idname == "GeometryNodeTree":
            return group
    group = bpy.data.node_groups.new(GROUP, "GeometryNodeTree")
    group[OWNER_KEY] = True
    group.inputs.new("NodeSocketGeometry", "Geometry")
    group.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = group.nodes, group.links
    source, sink = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    named = nodes.new("GeometryNodeInputNamedAttribute")
    named.data_type = "FLOAT_VECTOR"
    named.inputs["Name"].default_value = ATTRIBUTE
    setter = nodes.new("GeometryNodeSetPosition")
    links.new(source.outputs[0], setter.inputs["Geometry"])
    links.new(next(s for s in named.outputs if s.enabled), setter.inputs["Position"])
    links.new(setter.outputs[0], sink.inputs[0])
    return group


def modifier(model):
    """The model's "mbi" modifier, made first in its stack when missing."""
    found = model.modifiers.get(MODIFIER)
    if found is not None and found.type == "NODES":
        if found.node_group is None:
            found.node_group = node_group()
        return found
    made = model.modifiers.new(MODIFIER, "NODES")
    made.node_group = node_group()
    if model.modifiers[0] != made:
        with bpy.context.temp_override(object=model):
            bpy.ops.object.modifier_move_to_index(modifier=made.name, index=0)
    return made


def show(model, on):
    found = model.modifiers.get(MODIFIER)
    if found is not None:
        found.show_viewport = found.show_render = on


def remove(model):
    found = model.modifiers.get(MODIFIER)
    group = found.node_group if found is not None else None
    if found is not None:
        model.modifiers.remove(found)
    if group is not None and group.get(OWNER_KEY) and group.users == 0:
        bpy.data.node_groups.remove(group)
    if ATTRIBUTE in model.data.attributes:
        model.data.attributes.remove(model.data.attributes[ATTRIBUTE])
