# SPDX-License-Identifier: GPL-3.0-or-later
"""welkin.update_sky, welkin.remove_sky, welkin.export_hdri.

Every problem the user can fix ends as an operator report (ERROR: the operator is
cancelled and nothing changed; WARNING: done, but look), never as a traceback. From
scripts, bpy.ops raises RuntimeError carrying the ERROR report's text, as for any
operator."""

import os

import bpy
from bpy_extras.io_utils import ExportHelper

from ... import sky_compute
from . import scene_sun, update
from .scene_sun import UserError


def _report_warnings(operator, warnings):
    for warning in warnings:
        operator.report({"WARNING"}, f"Welkin: {warning}")
        print(f"Welkin: warning: {warning}")


def _fail(operator, error):
    operator.report({"ERROR"}, f"Welkin: {error}")
    print(f"Welkin: error: {error}")
    return {"CANCELLED"}


class WELKIN_OT_update_sky(bpy.types.Operator):
    """Compute the sky for the sun lamp and put it into the world (the world's own nodes
    are kept); sync the lamp"""

    bl_idname = "welkin.update_sky"
    bl_label = "Update Sky"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)

        def progress(fraction):
            # A cloudy sky takes seconds: the cursor shows how far it is.
            wm.progress_update(fraction)
            return True

        if context.scene.world is not None:
            # Cloud layers added or removed from Python (layers.add()) do not tag the world
            # for the depsgraph: its evaluated copy would still hold the old layers.
            context.scene.world.update_tag()
        try:
            outcome = update.update_sky(
                context.scene, context.evaluated_depsgraph_get(), force=True, pack=True, progress=progress
            )
        except UserError as error:
            return _fail(self, error)
        except KeyboardInterrupt:
            return _fail(self, "cancelled: the sky was not changed")
        finally:
            wm.progress_end()
        _report_warnings(self, outcome.warnings)
        self.report({"INFO"}, f"Welkin: {context.scene.world.welkin.status}")
        return {"FINISHED"}


class WELKIN_OT_remove_sky(bpy.types.Operator):
    """Take the Welkin sky out of the world: its nodes and images go, the world's own
    output is active again"""

    bl_idname = "welkin.remove_sky"
    bl_label = "Remove Sky"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            update.remove_sky(context.scene)
        except UserError as error:
            return _fail(self, error)
        return {"FINISHED"}


class WELKIN_OT_export_hdri(bpy.types.Operator, ExportHelper):
    """Write the sky the world shows (its clouds included, the sun's disc optional) as an
    equirectangular OpenEXR HDRI"""

    bl_idname = "welkin.export_hdri"
    bl_label = "Export HDRI"
    bl_options = {"REGISTER"}

    filename_ext = ".exr"
    filter_glob: bpy.props.StringProperty(default="*.exr", options={"HIDDEN"})
    width: bpy.props.IntProperty(
        name="Width",
        default=0,
        min=0,
        max=16384,
        description="Width in pixels, even (height = width / 2); 0: the world's resolution",
    )
    half: bpy.props.BoolProperty(
        name="Half Float", default=False, description="16-bit floats (values beyond 65504 clamped)"
    )
    sun_disc: bpy.props.BoolProperty(
        name="Sun Disc",
        default=True,
        description="Include the sun's disc (energy-exact), so the HDRI alone lights a scene",
    )
    overwrite: bpy.props.BoolProperty(name="Overwrite", default=False, description="Replace an existing file")

    def execute(self, context):
        try:
            module = update.module_or_error()
            if not self.filepath:
                raise UserError("filepath: give the .exr file to write")
            path = bpy.path.abspath(self.filepath)
            if os.path.exists(path) and not self.overwrite:
                raise UserError(f"filepath: '{path}' exists; tick Overwrite (overwrite=True) to replace it")
            scene = context.scene
            world = scene.world
            if world is None:
                raise UserError("the scene has no world: add one, or run Update Sky first")
            depsgraph = context.evaluated_depsgraph_get()
            request, _lamp, warnings = scene_sun.request_for(scene, world.welkin, depsgraph)
            width = self.width or request.width
            if width < 4 or width % 2:
                raise UserError(f"width: must be even and in [4, 16384] (or 0), got {width}")
            # The clouds the world shows (its layers and the volumes it holds), seen from
            # where the world's sky is seen from.
            clouds = update.clouds_of(scene, depsgraph)
            scene_json = (
                update.cloudy_scene_json(scene, world.welkin, request, clouds, module, depsgraph)
                if clouds
                else None
            )
            wm = context.window_manager
            wm.progress_begin(0.0, 1.0)
            try:
                pixels = sky_compute.hdri(
                    module,
                    request,
                    width,
                    sun_disc=self.sun_disc,
                    scene_json=scene_json,
                    progress=lambda f: wm.progress_update(f) or True,
                )
            finally:
                wm.progress_end()
            clamped = module.write_exr(
                path,
                pixels,
                half=self.half,
                overwrite=self.overwrite,
                attributes=[
                    ("software", f"welkin {module.__version__} (Blender add-on)"),
                    ("welkinRequest", repr(request)),
                ],
            )
        except UserError as error:
            return _fail(self, error)
        except (ValueError, OSError) as error:
            return _fail(self, error)
        except KeyboardInterrupt:
            return _fail(self, "cancelled: no file was written")
        _report_warnings(self, warnings)
        if clamped:
            _report_warnings(
                self, [f"{clamped} values above 65504 (the sun's disc) were clamped in the half-float file"]
            )
        self.report({"INFO"}, f"Welkin: wrote {path} ({width} x {width // 2})")
        return {"FINISHED"}
