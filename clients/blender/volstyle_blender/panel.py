"""The sidebar tab: View3D ▸ N ▸ volstyle."""
import bpy


class VOLSTYLE_PT_panel(bpy.types.Panel):
    bl_label, bl_idname = "volstyle", "VOLSTYLE_PT_panel"
    bl_space_type, bl_region_type, bl_category = "VIEW_3D", "UI", "volstyle"

    def draw(self, context):
        s = context.scene.volstyle
        col = self.layout.column(align=True)
        col.prop(s, "url")
        addon = context.preferences.addons.get(__package__)
        if addon:
            col.prop(addon.preferences, "token")  # saved with the preferences, not the .blend
        col.operator("volstyle.connect", icon="URL")
        box = self.layout.box()
        box.label(text="1. Volume", icon="VOLUME_DATA")
        row = box.row(align=True)
        row.operator("volstyle.send_volume", text="Send selected").builtin = False
        row.operator("volstyle.send_volume", text="Built-in cloud").builtin = True
        row = box.row(align=True)
        row.prop(s, "builtin_scene", text="")
        row.prop(s, "builtin_resolution")
        if s.session:
            box.label(text=f"session {s.session[:8]} · {s.volume_object.name if s.volume_object else '?'}")
        box = self.layout.box()
        box.label(text="2. Paint", icon="BRUSH_DATA")
        box.operator("volstyle.render_views", icon="CAMERA_DATA")
        box.prop(s, "keep_rest")
        box.operator("volstyle.send_targets", icon="EXPORT")
        box = self.layout.box()
        box.label(text="3. Solve", icon="PLAY")
        box.prop(s, "unknowns")
        box.prop(s, "iterations")
        box.prop(s, "anisotropy")
        box.prop(s, "import_each_solve")
        row = box.row(align=True)
        row.operator("volstyle.solve", icon="PLAY")
        row.operator("volstyle.cancel", icon="CANCEL")
        box.operator("volstyle.import_result", icon="IMPORT")
        self.layout.operator("volstyle.shafts", icon="LIGHT_SUN")
        if s.status:
            self.layout.label(text=s.status)


CLASSES = [VOLSTYLE_PT_panel]
