# SPDX-License-Identifier: GPL-3.0-or-later
"""Properties > World > Welkin Sky."""

import textwrap

import bpy

from ... import native


def _wrapped(layout, text, icon="NONE", width=60):
    col = layout.column(align=True)
    for i, line in enumerate(textwrap.wrap(text, width)):
        col.label(text=line, icon=icon if i == 0 else "BLANK1")


class WORLD_PT_welkin_sky(bpy.types.Panel):
    bl_label = "Welkin Sky"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"

    @classmethod
    def poll(cls, context):
        return context.world is not None

    def draw(self, context):
        layout = self.layout
        message = native.message()
        if message:
            _wrapped(layout, message, icon="ERROR")
            return
        s = context.world.welkin
        layout.use_property_split = True
        col = layout.column()
        col.prop(s, "preset")
        sub = col.column(align=True)
        sub.prop(s, "air_density")
        sub.prop(s, "aerosol_density")
        sub.prop(s, "ozone_density")
        col.prop(s, "aerosol_input")
        if s.aerosol_input == "OPTICAL_DEPTH":
            col.prop(s, "aerosol_optical_depth")
        elif s.aerosol_input == "TURBIDITY":
            col.prop(s, "turbidity")
        col.prop(s, "use_preset_albedo")
        row = col.row()
        row.active = not s.use_preset_albedo
        row.prop(s, "ground_color")
        col.separator()
        col.prop(s, "altitude_m")
        col.prop(s, "use_camera_height")
        col.prop(s, "sun_object")
        col.prop(s, "sync_lamp")
        col.prop(s, "show_sun_disc")
        col.prop(s, "show_ground")
        col.separator()
        col.prop(s, "exposure")
        col.prop(s, "resolution")
        col.prop(s, "method")
        col.prop(s, "colour")
        col.prop(s, "auto_update")
        lamp = s.sun_object
        animated = lamp is not None and lamp.animation_data is not None
        if s.auto_update and animated and not context.scene.render.use_lock_interface:
            box = layout.box()
            _wrapped(box, "Animated sun: UI renders follow it only with Lock Interface on", icon="INFO")
            box.prop(context.scene.render, "use_lock_interface")
        row = layout.row(align=True)
        row.operator("welkin.update_sky", icon="WORLD")
        row.operator("welkin.remove_sky", icon="X")
        layout.operator("welkin.export_hdri", icon="EXPORT")
        if s.status:
            _wrapped(layout, s.status, icon="INFO")
        for warning in filter(None, s.warnings.split("\n")):
            _wrapped(layout, warning, icon="ERROR")
