# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene.welkin_aerial: aerial perspective's settings (Properties > Render > Welkin Aerial
Perspective) and the state the add-on keeps in the file. Turning it on or off installs or
removes everything (scene.py)."""

import bpy

from . import scene as aerial_scene


def _toggled(settings, context):
    scene = settings.id_data  # the Scene that owns these settings
    if settings.enabled:  # (Write Pass Files alone, with aerial perspective off, does nothing)
        aerial_scene.enable(scene)
    else:
        aerial_scene.disable(scene)


class WelkinAerialSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(
        name="Aerial Perspective",
        default=False,
        update=_toggled,
        description="Haze the rendered frame with Welkin's aerial perspective (adds a node "
        "group to the materials, two shader AOVs and a compositor group)",
    )
    side_files: bpy.props.BoolProperty(
        name="Write Pass Files",
        default=False,
        update=_toggled,
        description="Also write the passes (and the clouds marched up to the geometry), the "
        "frame's scene JSON and the hazed frame beside every render, from the Z "
        "pass (turns the Z pass on)",
    )
    method: bpy.props.EnumProperty(
        name="Method",
        default="froxel",
        items=(
            ("froxel", "Froxels", "Hillaire 2020 camera volume (fast)"),
            ("raymarch", "Ray march", "Every pixel marched (reference, slow)"),
        ),
    )
    status: bpy.props.StringProperty(options={"HIDDEN"})
    nodes_installed: bpy.props.BoolProperty(options={"HIDDEN"})
    previous_use_pass_z: bpy.props.BoolProperty(options={"HIDDEN"})
    compositor_undo: bpy.props.StringProperty(options={"HIDDEN"})
    added_aovs: bpy.props.StringProperty(options={"HIDDEN"})
