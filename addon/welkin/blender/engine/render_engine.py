# SPDX-License-Identifier: GPL-3.0-or-later
"""The Welkin render engine ("WELKIN"): the active camera's plate of sky, sun disc and
aerial perspective over the ground at the scene's ground altitude, no meshes.

render() writes the scene description (plate.scene_json) from the world's Welkin
settings, its cloud layers, the marked cloud volumes, the sun lamp and the camera, has the
core render it (welkin.camera_plate, the same plate as `welkin plate --scene`), and hands
Blender the passes in bands of rows: Combined, Welkin.Sky, Welkin.AerialInscatter,
Welkin.AerialTransmittance, Welkin.Clouds and Welkin.CloudDepth (transparent and 1e10
without clouds). Errors (no camera, no world, a camera below the ground, a marked volume
whose VDB file is missing, the compiled module missing) are reported
with self.report({'ERROR'}) and no result is written; a cancelled render (Esc,
test_break) stops the core. The plate, clear or cloudy, is computed in tiles of BAND_ROWS
rows (welkin.CameraPlateRenderer: the frame-wide part once, then render(rows=...) per
tile, with the whole frame's values), each shown as soon as it is done, with
update_progress and test_break between tiles. view_update / view_draw: the viewport
preview (blender/engine/viewport.py), the same plate for the viewport's view.
"""

import bpy

from ... import plate, sky_request
from ..clouds import scene as cloud_scene
from .. import compat
from ..sky import scene_sun, update
from . import viewport as viewport_preview
from ..sky.scene_sun import UserError

BAND_ROWS = 64


def _camera_data(cam):
    data = {
        k: getattr(cam, k)
        for k in (
            "type",
            "lens",
            "sensor_width",
            "sensor_height",
            "sensor_fit",
            "ortho_scale",
            "shift_x",
            "shift_y",
            "clip_start",
            "clip_end",
        )
    }
    if cam.type == "PANO":
        source = compat.camera_panorama(cam)
        if source is None:
            raise UserError(
                "panoramic camera: its panorama settings need the Cycles add-on (enabled by default)"
            )
        for k in ("panorama_type", "latitude_min", "latitude_max", "longitude_min", "longitude_max"):
            data[k] = getattr(source, k)
        if data["panorama_type"] != "EQUIRECTANGULAR":
            raise UserError(
                f"camera '{cam.name}': panorama type {data['panorama_type']} is not "
                f"supported; Welkin renders EQUIRECTANGULAR panoramas"
            )
    return data


def scene_world(scene, depsgraph, native):
    """What the plate sees besides the camera: a dict of plate.scene_json's arguments
    (atmosphere, altitude, sun, exposure, method, clouds) from the world's Welkin settings,
    the sun lamp and the clouds at this frame; UserError for what the user can fix."""
    if scene.world is None:
        raise UserError(
            "the scene has no world: add one (World properties); its Welkin Sky settings drive the plate"
        )
    settings = scene.world.welkin
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, depsgraph)
    sky_request.validate(request, native)
    atm = sky_request.build_atmosphere(request, native)
    # The world's cloud layers and the marked volumes at this frame (a missing VDB file is
    # a UserError naming the object and the path: no frame is written).
    clouds = cloud_scene.frame_clouds(scene, depsgraph)
    return {
        "atmosphere_json": atm.to_json_string(),
        "origin_altitude_m": settings.altitude_m,
        "sun_direction": tuple(request.sun_direction),
        "exposure": request.exposure,
        "method": sky_request.resolve_method(request.method, native),
        "clouds": clouds,
        "color_space": request.color_space,
    }


def scene_description_json(scene, depsgraph, native):
    """The frame's scene JSON (docs/pipelines.md "Scene JSON"); UserError for what the user can fix."""
    if scene.camera is None:
        raise UserError(
            "the scene has no active camera: add one (Add > Camera) and make it active (Ctrl+Numpad 0)"
        )
    world = scene_world(scene, depsgraph, native)
    camera = scene.camera.evaluated_get(depsgraph)
    if camera.type != "CAMERA":
        raise UserError(f"the active camera '{camera.name}' is not a camera object")
    cam = plate.camera_dict(camera.matrix_world, _camera_data(camera.data), scene.unit_settings.scale_length)
    r = scene.render
    if r.use_border:
        raise UserError(
            "render region (Output > Format > Render Region) is not supported by "
            "the Welkin engine: turn it off to render the full frame"
        )
    return plate.scene_json(
        camera=cam, resolution=(r.resolution_x, r.resolution_y, r.resolution_percentage), **world
    )


def _set_rect(render_pass, rect):
    """Fills a render pass from an (n, channels) float32 array by foreach_set, a copy of the
    buffer (assignment converts every value: 0.26 s a band of 1920 x 64 in Blender 5.3,
    against 1 ms). Blender 4.2 and later take the values flat (n x channels of them), 3.4
    the (n, channels) array; each refuses the other's shape by its size before any copy.
    Assignment only where neither is taken. Returns the way it wrote ("flat", "rows" or
    "assigned"), which the tests check."""
    import numpy as np

    rect = np.ascontiguousarray(rect, dtype=np.float32)  # foreach_set takes float32 only
    rows = render_pass.rect
    for name, values in (("flat", rect.reshape(-1)), ("rows", rect)):
        try:
            rows.foreach_set(values)
            return name
        except (AttributeError, TypeError):
            continue
    render_pass.rect = rect
    return "assigned"


class WelkinRenderEngine(bpy.types.RenderEngine):
    bl_idname = "WELKIN"
    bl_label = "Welkin"
    bl_use_postprocess = True
    bl_use_preview = False

    def __init__(self, *args, **kwargs):
        # Blender 4.4+ passes arguments that bpy_struct's __init__ must receive; 3.4-4.3
        # pass none (the same code runs on both).
        super().__init__(*args, **kwargs)
        self.preview = None

    def __del__(self):
        preview = getattr(self, "preview", None)
        if preview is not None:
            preview.stop()

    # The viewport preview (Rendered shading): blender/engine/viewport.py.
    def view_update(self, context, depsgraph):
        if self.preview is None:
            self.preview = viewport_preview.Preview(self, scene_world)
        self.preview.update(context, depsgraph)

    def view_draw(self, context, depsgraph):
        if self.preview is None:
            self.preview = viewport_preview.Preview(self, scene_world)
            self.preview.update(context, depsgraph)
        self.preview.draw(self, context, depsgraph)

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        for name, channels, chan_id, _source in plate.PASSES:
            kind = "VALUE" if channels == 1 else ("VECTOR" if channels == 3 else "COLOR")
            self.register_pass(scene, renderlayer, name, channels, chan_id, kind)

    def render(self, depsgraph):
        import numpy as np

        scene = depsgraph.scene
        try:
            native = update.module_or_error()
            text = scene_description_json(scene, depsgraph, native)
            description = native.SceneDescription.from_json_string(text)
        except (UserError, ValueError) as error:
            self.report({"ERROR"}, f"Welkin: {error}")
            return
        cloudy = bool(getattr(description, "has_clouds", False))
        self.update_stats(
            "Welkin",
            "sky, sun, clouds and aerial perspective" if cloudy else "sky, sun and aerial perspective",
        )
        width, height = description.width, description.height
        for name, channels, chan_id, _source in plate.PASSES:
            self.add_pass(name, channels, chan_id)
        try:
            # The frame-wide part once (depth, sky method, aerial LUTs and volume); then
            # tiles of BAND_ROWS rows, each handed to Blender as soon as it is done.
            renderer = native.CameraPlateRenderer(description)
        except (ValueError, OSError) as error:
            self.report({"ERROR"}, f"Welkin: {error}")
            return
        except KeyboardInterrupt:
            return
        done = 0
        for rows, _y, h in plate.bands(height, BAND_ROWS):

            def progress(fraction, done=done, h=h):
                self.update_progress((done + fraction * h) / height)
                return not self.test_break()

            if self.test_break():
                return
            try:
                result = renderer.render(rows=rows, progress=progress)
            except (ValueError, OSError) as error:
                self.report({"ERROR"}, f"Welkin: {error}")
                return
            except KeyboardInterrupt:
                return  # cancelled (the core raises KeyboardInterrupt): nothing more is written
            self._hand_over(np, result, rows, width, height)
            done += h
            self.update_progress(done / height)

    def _hand_over(self, np, result, rows, width, height):
        """The plate of rows [r0, r1) (from the top) into Blender, in bands of BAND_ROWS."""
        r0, r1 = rows
        for sub, _y, h in plate.bands(r1 - r0, BAND_ROWS):
            local = (sub[0], sub[1])
            band = self.begin_result(0, height - (r0 + sub[1]), width, h)
            layer = band.layers[0]
            _set_rect(layer.passes["Combined"], plate.pass_rect(np, result, "combined", 4, local))
            for name, channels, _chan_id, source in plate.PASSES:
                _set_rect(layer.passes[name], plate.pass_rect(np, result, source, channels, local))
            self.end_result(band)


def _panels():
    """Properties panels that show with Welkin as the engine (render, output, world,
    camera data): those that list Cycles' or Eevee's engines in COMPAT_ENGINES."""
    out = []
    for name in dir(bpy.types):
        panel = getattr(bpy.types, name)
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if (
            engines is not None
            and ("CYCLES" in engines or any(e in engines for e in compat.eevee_engine_ids()))
            and (
                name.startswith(
                    (
                        "RENDER_PT_dimensions",
                        "RENDER_PT_format",
                        "RENDER_PT_output",
                        "DATA_PT_camera",
                        "DATA_PT_lens",
                        "WORLD_PT",
                    )
                )
            )
        ):
            out.append(panel)
    return out


def register():
    for panel in _panels():
        panel.COMPAT_ENGINES.add("WELKIN")


def unregister():
    for panel in _panels():
        panel.COMPAT_ENGINES.discard("WELKIN")
