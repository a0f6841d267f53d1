# SPDX-License-Identifier: GPL-3.0-or-later
"""Properties > World > Welkin Clouds, and Object > Properties > Welkin Cloud (Volume
objects only)."""

import bpy

from . import scene as cloud_scene


class WELKIN_UL_cloud_layers(bpy.types.UIList):
    def draw_item(
        self, _context, layout, _data, item, _icon, _active_data, _active_prop, _index=0, _flt_flag=0
    ):
        row = layout.row(align=True)
        row.prop(item, "enabled", text="")
        row.prop(item, "name", text="", emboss=False)


class WORLD_PT_welkin_clouds(bpy.types.Panel):
    bl_label = "Welkin Clouds"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "world"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return context.world is not None

    def draw(self, context):
        layout = self.layout
        s = context.world.welkin_clouds
        row = layout.row()
        row.template_list("WELKIN_UL_cloud_layers", "", s, "layers", s, "active_layer", rows=2)
        col = row.column(align=True)
        col.operator("welkin.add_cloud_layer", icon="ADD", text="")
        col.operator("welkin.remove_cloud_layer", icon="REMOVE", text="")
        layout.use_property_split = True
        if 0 <= s.active_layer < len(s.layers):
            layer = s.layers[s.active_layer]
            col = layout.column()
            col.active = layer.enabled
            col.prop(layer, "cloud_type")
            sub = col.column(align=True)
            sub.prop(layer, "bottom_altitude_m")
            sub.prop(layer, "top_altitude_m")
            col.prop(layer, "coverage")
            col.prop(layer, "coverage_measure")
            col.prop(layer, "density_per_m")
            sub = col.column(align=True)
            sub.prop(layer, "base_scale_m")
            sub.prop(layer, "detail_scale_m")
            sub.prop(layer, "weather_scale_m")
            col.prop(layer, "detail_strength")
            col.prop(layer, "weather_variation")
            col.prop(layer, "wind_offset_m")
            col.prop(layer, "evolution_m")
            col.prop(layer, "seed")
        layout.separator()
        col = layout.column()
        col.prop(s, "albedo")
        sub = col.column(align=True)
        sub.prop(s, "max_steps")
        sub.prop(s, "light_steps")
        sub.prop(s, "ambient_steps")
        col.prop(s, "octaves")
        layout.separator()
        col = layout.column()
        col.prop(s, "shadows")
        col.prop(s, "ground_shadows")
        sub = col.column(align=True)
        sub.active = s.ground_shadows
        sub.prop(s, "shadow_extent_m")
        sub.prop(s, "shadow_height_m")
        sub.prop(s, "shadow_resolution")
        layout.separator()
        layout.label(text="Volume objects marked as clouds:")
        volumes = cloud_scene.marked_volumes(context.scene)
        box = layout.box()
        if not volumes:
            box.label(text="none (select Volume objects, then Mark)", icon="INFO")
        for ob in volumes:
            box.label(text=f"{ob.name}: grid '{ob.welkin_cloud.grid}'", icon="VOLUME_DATA")
        layout.prop(s, "volumes_in_world")
        row = layout.row(align=True)
        row.operator("welkin.mark_cloud_volumes", icon="ADD")
        row.operator("welkin.unmark_cloud_volumes", icon="REMOVE")


class OBJECT_PT_welkin_cloud(bpy.types.Panel):
    bl_label = "Welkin Cloud"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "VOLUME"

    def draw_header(self, context):
        self.layout.prop(context.object.welkin_cloud, "enabled", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        c = context.object.welkin_cloud
        col = layout.column()
        col.active = c.enabled
        col.prop(c, "grid")
        col.prop(c, "density_scale")


classes = (WELKIN_UL_cloud_layers, WORLD_PT_welkin_clouds, OBJECT_PT_welkin_cloud)
