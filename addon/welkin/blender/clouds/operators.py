# SPDX-License-Identifier: GPL-3.0-or-later
"""welkin.add_cloud_layer, welkin.remove_cloud_layer, welkin.mark_cloud_volumes,
welkin.unmark_cloud_volumes. Bad input (no world, no layer at that index, nothing selected,
an object that is not a Volume, a volume without a file) ends as a report, never a
traceback; from scripts bpy.ops raises RuntimeError carrying the ERROR report."""

import os

import bpy

from . import scene as cloud_scene


def _fail(operator, text):
    operator.report({"ERROR"}, f"Welkin: {text}")
    print(f"Welkin: error: {text}")
    return {"CANCELLED"}


def _world(context):
    return context.scene.world if context.scene is not None else None


class WELKIN_OT_add_cloud_layer(bpy.types.Operator):
    """Add a procedural cloud layer (Nubis-style cumulus by default) to the world"""

    bl_idname = "welkin.add_cloud_layer"
    bl_label = "Add Cloud Layer"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        world = _world(context)
        if world is None:
            return _fail(self, "the scene has no world: add one (World properties) first")
        settings = world.welkin_clouds
        layer = settings.layers.add()
        layer.name = f"Cloud Layer {len(settings.layers)}"
        settings.active_layer = len(settings.layers) - 1
        self.report({"INFO"}, f"Welkin: added '{layer.name}'")
        return {"FINISHED"}


class WELKIN_OT_remove_cloud_layer(bpy.types.Operator):
    """Remove the active procedural cloud layer"""

    bl_idname = "welkin.remove_cloud_layer"
    bl_label = "Remove Cloud Layer"
    bl_options = {"REGISTER", "UNDO"}

    index: bpy.props.IntProperty(
        name="Index", default=-1, description="The layer to remove (-1: the active one)"
    )

    def execute(self, context):
        world = _world(context)
        if world is None:
            return _fail(self, "the scene has no world")
        settings = world.welkin_clouds
        n = len(settings.layers)
        index = settings.active_layer if self.index < 0 else self.index
        if n == 0:
            return _fail(self, "the world has no cloud layer to remove")
        if not 0 <= index < n:
            return _fail(self, f"index: must be in [0, {n - 1}] (or -1 for the active layer), got {index}")
        settings.layers.remove(index)
        settings.active_layer = max(0, min(settings.active_layer, len(settings.layers) - 1))
        return {"FINISHED"}


def _selected(context):
    return list(getattr(context, "selected_objects", None) or ())


class WELKIN_OT_mark_cloud_volumes(bpy.types.Operator):
    """Mark the selected Volume objects as Welkin clouds (their VDB files are rendered by
    Welkin's sky, passes and render engine)"""

    bl_idname = "welkin.mark_cloud_volumes"
    bl_label = "Mark Selected Volumes"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        objects = _selected(context)
        if not objects:
            return _fail(self, "select the Volume objects to mark as Welkin clouds")
        bad = [o.name for o in objects if o.type != "VOLUME"]
        if bad:
            return _fail(
                self,
                f"not a Volume object: {', '.join(bad)} (only Volume objects "
                f"with a VDB file can be Welkin clouds); nothing marked",
            )
        for ob in objects:
            if not ob.data.filepath:
                return _fail(
                    self,
                    f"volume object '{ob.name}' has no VDB file (Object Data > OpenVDB File); nothing marked",
                )
        for ob in objects:
            ob.welkin_cloud.enabled = True
            path = cloud_scene.volume_path(ob.data, context.scene.frame_current)
            if path is not None and not os.path.isfile(path):
                self.report(
                    {"WARNING"},
                    f"Welkin: volume object '{ob.name}': its VDB file for "
                    f"frame {context.scene.frame_current} is missing: {path}",
                )
        self.report({"INFO"}, f"Welkin: {len(objects)} volume(s) marked as clouds")
        return {"FINISHED"}


class WELKIN_OT_unmark_cloud_volumes(bpy.types.Operator):
    """Unmark the selected objects (they are no longer Welkin clouds)"""

    bl_idname = "welkin.unmark_cloud_volumes"
    bl_label = "Unmark Selected Volumes"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        objects = [o for o in _selected(context) if o.type == "VOLUME" and o.welkin_cloud.enabled]
        if not objects:
            return _fail(self, "no selected Volume object is marked as a Welkin cloud")
        for ob in objects:
            ob.welkin_cloud.enabled = False
        return {"FINISHED"}


classes = (
    WELKIN_OT_add_cloud_layer,
    WELKIN_OT_remove_cloud_layer,
    WELKIN_OT_mark_cloud_volumes,
    WELKIN_OT_unmark_cloud_volumes,
)
