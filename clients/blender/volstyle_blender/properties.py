"""What the add-on remembers per scene (saved with the .blend): the server, the session, the
volume object that defines volstyle's space, and the solve's settings."""
import bpy


class VolstyleSettings(bpy.types.PropertyGroup):
    url: bpy.props.StringProperty(name="Server", default="http://127.0.0.1:8080", description="the volstyle server's address")
    session: bpy.props.StringProperty(name="Session", default="", description="the server session this scene edits")
    volume_object: bpy.props.PointerProperty(name="Volume", type=bpy.types.Object,
                                             description="the Volume object whose space is volstyle's world (its VDB was sent)")
    builtin_scene: bpy.props.EnumProperty(name="Built-in", default="cloud", items=[
        ("cloud", "Cloud", "a cumulus cloud: noise-perturbed blobs with a flat base"),
        ("plume", "Plume", "a rising, spreading smoke column"),
        ("sphere", "Sphere", "a sphere of smoke with a smooth falloff"),
        ("cube", "Cube", "a cube of constant extinction"),
    ])
    builtin_resolution: bpy.props.IntProperty(name="Resolution", default=64, min=8, max=256,
                                              description="voxels a side of a built-in cloud")
    unknowns: bpy.props.EnumProperty(name="Unknowns", default="emission,albedo", items=[
        ("emission,albedo", "Emission + albedo", "lighter, darker and other colours"),
        ("emission", "Emission", "only adds light"),
        ("albedo", "Albedo", "between black and white scattering"),
        ("extinction", "Extinction", "denser or thinner"),
    ])
    iterations: bpy.props.IntProperty(name="Iterations", default=30, min=1, max=2000)
    keep_rest: bpy.props.BoolProperty(name="Keep the rest", default=True,
                                      description="unpainted pixels hold the view as it rendered (weight 1); off: only the paint asks anything")
    anisotropy: bpy.props.FloatProperty(name="Anisotropy", default=0.0, min=-0.95, max=0.95,
                                        description="Henyey-Greenstein g of the medium's phase, sent with the lighting and set on the material")
    import_each_solve: bpy.props.BoolProperty(name="Import after solving", default=True)
    status: bpy.props.StringProperty(name="Status", default="")


class VolstylePreferences(bpy.types.AddonPreferences):
    """Kept with Blender's preferences, never in a .blend: the token."""
    bl_idname = __package__
    token: bpy.props.StringProperty(name="Token", default="", subtype="PASSWORD",
                                    description="the server's bearer token (empty: $VOLSTYLE_TOKEN or none)")

    def draw(self, context):
        self.layout.prop(self, "token")


CLASSES = [VolstyleSettings, VolstylePreferences]


def register():
    bpy.types.Scene.volstyle = bpy.props.PointerProperty(type=VolstyleSettings)


def unregister():
    del bpy.types.Scene.volstyle
