# SPDX-License-Identifier: GPL-3.0-or-later
"""Properties > Render > Welkin Aerial Perspective."""

import bpy


class RENDER_PT_welkin_aerial(bpy.types.Panel):
    bl_label = "Welkin Aerial Perspective"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        s = context.scene.welkin_aerial
        layout = self.layout
        layout.use_property_split = True
        layout.prop(s, "enabled")
        col = layout.column()
        col.active = s.enabled
        col.prop(s, "side_files")
        row = col.row()
        row.active = s.side_files
        row.prop(s, "method")
        row = layout.row(align=True)
        row.operator("welkin.bake_farm", icon="RENDER_ANIMATION")
        row.operator("welkin.clear_farm_bake", text="", icon="X")
        if s.status:
            layout.label(text=s.status, icon="INFO")
