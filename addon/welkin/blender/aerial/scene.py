# SPDX-License-Identifier: GPL-3.0-or-later
"""A scene's aerial perspective: turning it on and off, the frame's table baked for its
camera, sun and atmosphere (frame.py's nodes read it), the frame's scene JSON, and the
tables packed into a saved file. What it does in the frame and with Write Pass Files is in
this package's __init__.py."""

import json
import math

import bpy

from ... import native, scene_export, sky_request
from . import compositor, frame as aerial_frame
from ..clouds import scene as cloud_scene
from .. import compat
from ..sky import images, scene_sun
from ..sky.scene_sun import UserError


def log(scene, text):
    print(f"Welkin: {text}")
    scene.welkin_aerial.status = text


def base_of(scene):
    return scene_export.file_base(bpy.path.abspath(scene.render.filepath))


def _drop_farm_bake(scene):
    from .. import farm_bake

    if farm_bake.drop(scene, "aerial perspective was switched"):
        log(scene, "the farm bake was dropped: press Bake for Farm again before sending the file to a farm")


def enable(scene):
    s = scene.welkin_aerial
    _drop_farm_bake(scene)
    for warning in aerial_frame.install(scene, s):
        log(scene, warning)
    try:
        bake(scene)
    except UserError as error:
        log(scene, f"aerial perspective: {error}")
    if s.side_files:
        enable_side_files(scene)
    else:
        disable_side_files(scene)


def disable(scene):
    _drop_farm_bake(scene)
    disable_side_files(scene)
    aerial_frame.remove(scene, scene.welkin_aerial)
    baked.clear()


def bake(scene, depsgraph=None, text=None):
    """Bakes the frame's table (aerial_frame.bake) for the camera and sun as evaluated in
    `depsgraph` (or as they are now); raises UserError."""
    module = native.module()
    if module is None:
        raise UserError(native.message())
    if text is None:
        text = scene_json(scene, module, depsgraph)
    try:
        aerial_frame.bake(scene, module, text, scene.unit_settings.scale_length, baked)
    except (ValueError, OSError) as error:
        raise UserError(str(error)) from None


# image name -> the key of what it holds (kept in Python, not in the file: a file loads with
# the image's pixels blank)
baked = {}


def enable_side_files(scene):
    s = scene.welkin_aerial
    if not s.nodes_installed:
        s.previous_use_pass_z = all(layer.use_pass_z for layer in scene.view_layers)
    for layer in scene.view_layers:
        layer.use_pass_z = True
    for warning in compositor.install(scene, s, scene_export.file_output_base(base_of(scene))):
        log(scene, warning)


def disable_side_files(scene):
    s = scene.welkin_aerial
    was = s.nodes_installed
    if not was:
        return
    compositor.remove(scene, s)
    if was and not s.previous_use_pass_z:
        for layer in scene.view_layers:
            layer.use_pass_z = False


def camera_of(scene, depsgraph=None):
    ob = scene.camera
    if ob is None:
        raise UserError("no scene camera: set Scene > Camera (aerial perspective needs one)")
    if depsgraph is not None:
        ob = ob.evaluated_get(depsgraph)
    cam = ob.data
    panorama = None
    if cam.type == "PANO":
        c = compat.camera_panorama(cam)
        if c is None:
            raise UserError(
                "panoramic camera: its panorama settings need the Cycles add-on (enabled by default)"
            )
        if c.panorama_type != "EQUIRECTANGULAR":
            raise UserError(
                f"camera '{ob.name}': panorama type {c.panorama_type} is not "
                f"supported by aerial perspective (only EQUIRECTANGULAR)"
            )
        panorama = dict(
            panorama_type=c.panorama_type,
            latitude_min_deg=math.degrees(c.latitude_min),
            latitude_max_deg=math.degrees(c.latitude_max),
            longitude_min_deg=math.degrees(c.longitude_min),
            longitude_max_deg=math.degrees(c.longitude_max),
        )
    return scene_export.camera_dict(
        [list(r) for r in ob.matrix_world],
        cam.type,
        cam.lens,
        cam.sensor_width,
        cam.sensor_height,
        cam.sensor_fit,
        cam.ortho_scale,
        cam.shift_x,
        cam.shift_y,
        cam.clip_start,
        cam.clip_end,
        scale_length=scene.unit_settings.scale_length,
        panorama=panorama,
    )


def scene_json(scene, module, depsgraph=None):
    """The frame's scene JSON text (validated by the core), from the world's Welkin sky
    settings, the sun lamp the sky uses, the scene camera and the render size; the camera
    and lamp as evaluated in `depsgraph` when given (the render's own, at its frame)."""
    if scene.world is None:
        raise UserError(
            "the scene has no world: aerial perspective takes its atmosphere from World > Welkin Sky"
        )
    settings = scene.world.welkin
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, depsgraph)
    atmosphere = json.loads(sky_request.build_atmosphere(request, module).to_json_string())
    r = scene.render
    d = scene_export.scene_dict(
        atmosphere,
        settings.altitude_m,
        request.sun_direction,
        settings.exposure,
        sky_request.resolve_method(settings.method, module),
        camera_of(scene, depsgraph),
        (r.resolution_x, r.resolution_y, r.resolution_percentage),
        aerial={"method": scene.welkin_aerial.method},
        clouds=cloud_scene.clouds_section(scene, depsgraph),
        color_space=request.color_space,
    )
    return module.SceneDescription.from_json_string(json.dumps(d)).to_json_string()


def pack_tables(scene):
    """Bakes the table of the scene's current frame and packs its images into the .blend
    (save_pre), so that the saved file carries the haze it shows: a Blender without the
    add-on renders a scene whose camera, sun and atmosphere do not change over the frames
    as the add-on does (docs/pipelines.md#saved-files-without-the-add-on). Returns the
    problem, or None."""
    try:
        bake(scene)
    except UserError as error:
        return f"aerial perspective not saved with the file: {error}"
    names = aerial_frame.SCREEN_IMAGES if scene.render.engine == "CYCLES" else (aerial_frame.IMAGE,)
    for name in names:
        image = bpy.data.images.get(name)
        if image is None or not image.get(aerial_frame.MARK) or image.library is not None:
            continue
        if image.packed_file is None or image.is_dirty:
            images.pack(image)
    return None
