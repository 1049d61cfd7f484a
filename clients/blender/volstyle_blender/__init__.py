"""volstyle for Blender: paint how a volume should look, let a volstyle server solve for it, and
bring the result back as a Volume object (docs/CLIENTS.md).

The sidebar's volstyle tab (View3D ▸ N) connects to a server, sends the selected Volume object's
VDB (or a built-in cloud), renders each camera's view into an Image to paint with Texture Paint,
sends the paintings as targets, solves with progress in the status bar, and imports the solved
VDB with a material that renders it in Cycles and EEVEE as volstyle does. Light shafts: the
scene's meshes and sun go to the light-shaft stylizer and its frame comes back as an Image."""

bl_info = {
    "name": "volstyle",
    "author": "volstyle",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > volstyle",
    "description": "Restyle volumes by painting views: a client of the volstyle server",
    "doc_url": "https://github.com/volstyle/volstyle/blob/main/docs/CLIENTS.md",
    "category": "Render",
}

if "bpy" in locals():  # reloaded by Blender (F3 > Reload Scripts)
    import importlib

    from . import convert, material, operators, panel, pixels, properties, session  # noqa: F401

    for m in (convert, material, pixels, session, properties, operators, panel):
        importlib.reload(m)

import bpy  # noqa: E402

from . import operators, panel, properties  # noqa: E402

_classes = properties.CLASSES + operators.CLASSES + panel.CLASSES


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    properties.register()


def unregister():
    properties.unregister()
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
