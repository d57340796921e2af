"""What the add-on keeps on an object (saved in the .blend): its role, its cage and the bind options."""
import bpy

METHODS = [("modified-bi", "Modified BI", "Smooth, the default"),
           ("phong", "Phong", "Phong-style Bezier points"),
           ("bi", "BI", "Plain barycentric interpolation of Bezier points")]

INTERIOR = [("auto", "Auto", "Follow the boundary (harmonic) when only the boundary moved, else as animated"),
            ("harmonic", "Follow boundary", "Always the harmonic extension of the boundary's motion"),
            ("animated", "As animated", "Every node as Blender evaluated it")]

PIN_MOTIONS = [("held", "Held", "The pinned nodes stay where they are"),
               ("rigid", "Rigid motion", "The pinned nodes move rigidly: velocity plus a rotation about an axis"),
               ("object", "Follow object", "The pinned nodes move rigidly with an object's (or bone's) animated transform")]

COLLIDERS = [("none", "None", "Not an mbi collider"),
             ("plane", "Plane", "The plane through the object's origin, normal its local +Z (solid below)"),
             ("sphere", "Sphere", "Centered in the object's bounding box, radius its largest half extent"),
             ("box", "Box", "The object's bounding box, rotated with it"),
             ("capsule", "Capsule", "Along the bounding box's longest axis, radius the largest other half extent"),
             ("mesh", "Mesh", "The object's own closed triangle mesh (modifiers not applied), as a level set")]


class MbiObjectSettings(bpy.types.PropertyGroup):
    is_cage: bpy.props.BoolProperty(name="Is an mbi cage", default=False)
    interior: bpy.props.EnumProperty(name="Interior nodes", items=INTERIOR, default="auto",
                                     description="How a cage's interior nodes move (a cage's setting)")
    # physics of a cage (mbi.Simulator, SI units: a Blender unit is a metre)
    young: bpy.props.FloatProperty(name="Young's modulus (Pa)", default=1e5, min=1.0, max=1e13)
    poisson: bpy.props.FloatProperty(name="Poisson ratio", default=0.45, min=-0.99, max=0.499)
    density: bpy.props.FloatProperty(name="Density (kg/m^3)", default=1000.0, min=1e-3, max=1e5)
    mass_damping: bpy.props.FloatProperty(name="Mass damping (1/s)", default=0.0, min=0.0)
    stiffness_damping: bpy.props.FloatProperty(name="Stiffness damping (s)", default=0.0, min=0.0)
    substeps: bpy.props.IntProperty(name="Substeps", default=1, min=1, max=1000)
    pin_group: bpy.props.StringProperty(name="Pinned group",
                                        description="Vertex group of the cage's nodes held in place (weight > 0)")
    pin_motion: bpy.props.EnumProperty(name="Pinned motion", items=PIN_MOTIONS, default="held")
    pin_velocity: bpy.props.FloatVectorProperty(name="Velocity (m/s)", size=3, subtype="VELOCITY")
    pin_rate: bpy.props.FloatProperty(name="Angular velocity (rad/s)", default=0.0,
                                      description="Rotation rate about the axis through the center")
    pin_axis: bpy.props.FloatVectorProperty(name="Axis", size=3, default=(0.0, 0.0, 1.0), subtype="DIRECTION")
    pin_center: bpy.props.FloatVectorProperty(name="Center (m)", size=3, subtype="TRANSLATION",
                                              description="A point of the rotation axis, in world space")
    pin_start: bpy.props.FloatProperty(name="Start (s)", default=0.0, min=0.0,
                                       description="Seconds after the first frame when the motion starts")
    pin_stop: bpy.props.FloatProperty(name="Stop (s)", default=0.0, min=0.0,
                                      description="Seconds after the first frame when it stops (0: never)")
    pin_object: bpy.props.PointerProperty(name="Object", type=bpy.types.Object,
                                          description="The pinned nodes move rigidly with this object's transform")
    pin_bone: bpy.props.StringProperty(name="Bone", description="A bone of the armature the pins follow (empty: "
                                       "the object itself)")
    contact_stiffness: bpy.props.FloatProperty(name="Contact stiffness (N/m)", default=0.0, min=0.0,
                                               description="Penalty stiffness per touching vertex (0: mbi's "
                                               "default, 1e4 m g / diagonal)")
    # an object the simulated meshes touch (its shape fitted from its bounding box and transform)
    collider: bpy.props.EnumProperty(name="mbi collider", items=COLLIDERS, default="none")
    friction: bpy.props.FloatProperty(name="Friction", default=0.0, min=0.0, description="Coulomb coefficient")
    cage: bpy.props.PointerProperty(name="Cage", type=bpy.types.Object,
                                    description="The mbi cage this mesh is bound to")
    method: bpy.props.EnumProperty(name="Method", items=METHODS, default="modified-bi")
    alpha: bpy.props.FloatProperty(name="Alpha", default=0.0, min=0.0,
                                   description="Weight of modified-BI's E_vibr (0: the default, 0.1)")
    baked: bpy.props.BoolProperty(name="Baked", default=False,
                                  description="Played by its Mesh Cache modifier, not the live path")
    rest_hash: bpy.props.StringProperty(description="Hash of the rest content the bind was made from")
    bind_seconds: bpy.props.FloatProperty(description="Seconds of the last embedding and precompute")
    # the model's matrix in the cage's space at bind time (4x4, row-major): the bind is in cage space
    bind_matrix: bpy.props.FloatVectorProperty(size=16)


def register():
    bpy.utils.register_class(MbiObjectSettings)
    bpy.types.Object.mbi = bpy.props.PointerProperty(type=MbiObjectSettings)


def unregister():
    del bpy.types.Object.mbi
    bpy.utils.unregister_class(MbiObjectSettings)
