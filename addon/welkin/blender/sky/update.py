# SPDX-License-Identifier: GPL-3.0-or-later
"""One sky update, shared by the operator and the handlers: scene -> SkyRequest -> the
module -> the world's images and nodes, and the sun lamp.

Problems the user can fix raise scene_sun.UserError (nothing is changed then); warnings
(several sun lamps, sun below the horizon, camera below the ground) come back to be
reported. The world's user nodes are never touched (world_nodes.py); a world linked from a
library (or a library override of one) is refused before anything changes (not_editable);
the lamp's own colour, strength and angle are kept on its Light when Sync Lamp first
changes them, and remove_sky puts them back."""

import json

import bpy

from ... import native, scene_export, sky_compute, sky_request
from ..clouds import scene as cloud_scene, shadows as cloud_shadows
from . import images, place_time, scene_sun, world_nodes
from .scene_sun import UserError

WORLD_NAME = "Welkin World"
LAMP_KEY = "welkin_lamp_original"  # on a Light: [r, g, b, energy, angle] before Sync Lamp
SYNCED_KEY = "welkin_lamp_synced"  # on a Light: the values Sync Lamp last gave it


def _lamp_values(data):
    return [*data.color, data.energy, getattr(data, "angle", 0.0)]


def not_editable(world):
    """Why the add-on cannot change `world` (a message naming it and its library), or None.
    A world linked from a library is read-only: what the add-on would write (settings,
    nodes, images) is not saved with this file, and comes back from the library on reload.
    A library override keeps only the overridden properties, not the node tree or images."""
    if world is None:
        return None
    if world.library is not None:
        return (
            f"world '{world.name}' is linked from the library "
            f"'{world.library.filepath}' and cannot be changed here: make it local "
            f"(Outliner > right-click the world > Make Local) or update the sky in that "
            f"file; nothing was changed"
        )
    override = getattr(world, "override_library", None)
    if override is not None:
        reference = override.reference
        library = (
            reference.library.filepath
            if reference is not None and reference.library is not None
            else "its library"
        )
        return (
            f"world '{world.name}' is a library override of a world from "
            f"'{library}': its nodes and images cannot be saved with this file; make it "
            f"local (Outliner > right-click the world > Make Local) first; nothing was "
            f"changed"
        )
    return None


def refuse_if_not_editable(world):
    reason = not_editable(world)
    if reason is not None:
        raise UserError(reason)


class Outcome:
    def __init__(self):
        self.warnings = []
        self.updated = False
        self.seconds = 0.0
        self.method = ""


def module_or_error():
    module, message = native.load()
    if module is None:
        raise UserError(message)
    return module


def _world(scene):
    if scene.world is None:
        world = bpy.data.worlds.new(WORLD_NAME)
        world["welkin_created"] = True
        scene.world = world
    return scene.world


def _sync_lamp(lamp, values, depsgraph):
    data = lamp.data
    if depsgraph is not None and depsgraph.mode == "RENDER":
        # A render's own depsgraph (frame_change_post during `-a` or F12): write the
        # lamp's values into its evaluated copy, which Cycles reads, and leave the
        # original alone. Editing the original would make Blender evaluate that
        # depsgraph a second time, and the second pass re-copies the lamp object from
        # the original without re-animating it: the frame would render the new strength
        # from the old direction (seen: frame 10 lit from frame 1). The images need no
        # such care: Cycles reads the original image's pixels.
        data = lamp.evaluated_get(depsgraph).data
    elif LAMP_KEY not in data:
        # The lamp's own values, kept the first time Sync Lamp changes them (remove_sky).
        data[LAMP_KEY] = _lamp_values(data)
    data.color = values.color
    data.energy = values.strength_w_m2
    data.angle = values.angle_rad
    if data == lamp.data:
        data[SYNCED_KEY] = _lamp_values(data)  # as stored (float32), for remove_sky


def clouds_of(scene, depsgraph=None):
    """The "clouds" section of the world's sky at the current frame, or None (clear sky):
    the enabled layers, and the marked volumes only with Volumes in World Sky (Cycles and
    EEVEE render a volume object themselves; cloud_scene.volumes_in_world)."""
    volumes = cloud_scene.volumes_in_world(scene)
    if not cloud_scene.has_clouds(scene, volumes=volumes):
        return None
    return cloud_scene.clouds_section(scene, depsgraph, with_volumes=volumes)


def sky_key(settings, request, clouds):
    """Changes whenever the world's images would: the request, the disc and lamp switches,
    and the clouds (their layers, and each volume's file for the frame and placement)."""
    # "disc nodes": a file saved while the disc was an image, or before the moon's disc
    # was drawn, gets its nodes at the first update.
    c = settings.id_data.welkin_clouds
    key = request.key() + repr(
        (
            settings.show_sun_disc,
            settings.sync_lamp,
            "disc and moon disc nodes",
            c.shadows,
            c.ground_shadows and (c.shadow_extent_m, c.shadow_height_m, c.shadow_resolution),
        )
    )
    if clouds:
        key += json.dumps(clouds, sort_keys=True)
    return key


def cloudy_scene_json(scene, settings, request, clouds, module, depsgraph=None):
    """The scene description of the world's cloudy sky (docs/pipelines.md "Scene JSON"), re-centred on
    the observer: the world texture is the sky seen from the scene camera (with Add Camera
    Height on and a camera; else from the scene origin), and the core renders a scene's sky
    from its origin. So the origin moves to the camera: origin_altitude_m is the observer's
    altitude (as the clear sky's), each volume's placement is translated by minus the
    camera's position, and each layer's wind offset by minus its horizontal position (the
    layer's field is f(x - wind), so seen from the camera it is f(x' - (wind - camera))).
    A plain change of frame: every number is still the core's."""
    atmosphere = json.loads(sky_request.build_atmosphere(request, module).to_json_string())
    cx = cy = 0.0
    if settings.use_camera_height and scene.camera is not None:
        camera = scene.camera.evaluated_get(depsgraph) if depsgraph is not None else scene.camera
        s = scene.unit_settings.scale_length
        cx, cy = (float(v) * s for v in camera.matrix_world.translation[:2])
    cz = request.altitude_m - settings.altitude_m  # the camera height the sky uses
    moved = json.loads(json.dumps(clouds))
    for layer in moved["layers"]:
        layer["wind_offset_m"] = [layer["wind_offset_m"][0] - cx, layer["wind_offset_m"][1] - cy]
    for volume in moved["volumes"]:
        for row, c in zip(volume["matrix_world"][:3], (cx, cy, cz)):
            row[3] -= c
    return _sky_scene_json(scene, request, module, atmosphere, request.altitude_m, moved)


def shadow_scene_json(scene, settings, request, clouds, module):
    """The scene description of the clouds that shade the sun lamp (the world's clouds,
    `clouds`), centred on the scene origin (origin_altitude_m: the world's Altitude), or
    None when there are none or neither Shade Sun Lamp nor Ground Shadows is on. Its sun
    is the request's."""
    c = scene.world.welkin_clouds
    if not clouds or not (c.shadows or c.ground_shadows):
        return None
    atmosphere = json.loads(sky_request.build_atmosphere(request, module).to_json_string())
    return _sky_scene_json(scene, request, module, atmosphere, settings.altitude_m, clouds)


def _sky_scene_json(scene, request, module, atmosphere, origin_altitude_m, clouds):
    """The scene description (JSON text) of the request's sky with `clouds`, its origin at
    origin_altitude_m, without a camera: what cloudy_scene_json and shadow_scene_json share."""
    r = scene.render
    d = scene_export.scene_dict(
        atmosphere,
        origin_altitude_m,
        request.sun_direction,
        request.exposure,
        sky_request.resolve_method(request.method, module),
        None,
        (r.resolution_x, r.resolution_y, r.resolution_percentage),
        clouds=clouds,
        color_space=request.color_space,
    )
    del d["camera"]
    return json.dumps(d)


def shadow_options(scene, module):
    """The keyword arguments of sky_compute.compute for the world's cloud shadows
    (shade_lamp, shadow_map)."""
    c = scene.world.welkin_clouds
    if not c.ground_shadows:
        return {"shade_lamp": c.shadows, "shadow_map": None}
    extent, height, n = c.shadow_extent_m, c.shadow_height_m, c.shadow_resolution
    return {
        "shade_lamp": c.shadows,
        "shadow_map": lambda text: cloud_shadows.shadow_map(module, text, extent, height, n),
    }


def current_lamp(module, request, settings):
    """The lamp's values for `request` under the clouds of the last sky update (the
    transmittance it kept), without recomputing anything: cheap."""
    lamp = sky_compute.lamp_for(module, request)
    clouds = settings.id_data.welkin_clouds
    return sky_compute.shaded_lamp(lamp, clouds.lamp_transmittance) if clouds.shadows else lamp


def update_sky(scene, depsgraph=None, *, force=False, pack=True, progress=None, live=False):
    """Brings the world's sky up to date with the scene. Returns an Outcome. `progress`:
    callable(fraction) -> bool for a cloudy sky (seconds); `live`: a cloudy sky is not
    computed here (it would hold the interface for seconds at every nudge of the lamp; the
    UI's timer computes it beside the interface, background.py), the status says so."""
    module = module_or_error()
    outcome = Outcome()
    from .. import farm_bake

    if farm_bake.drop(scene, "the sky was updated"):  # its nodes read the live image again
        outcome.warnings.append(
            "the farm bake was dropped: press Bake for Farm again before sending the file to a farm"
        )
    if scene.world is None:
        scene_sun.choose_sun(scene, None)  # no sun lamp: refuse before adding a world
    world = _world(scene)
    settings = world.welkin
    request, lamp, outcome.warnings = scene_sun.request_for(scene, settings, depsgraph)
    place_time.place_lamps(scene, request, lamp, depsgraph, sync=_sync_lamp if settings.sync_lamp else None)
    clouds = clouds_of(scene, depsgraph)
    key = sky_key(settings, request, clouds)
    render_graph = depsgraph is not None and depsgraph.mode == "RENDER"
    if (
        not force
        and settings.active
        and settings.last_key == key
        and settings.sky_image is not None
        and images.owned(settings)
    ):
        if render_graph and settings.sync_lamp:
            # The sky is current, but this render's evaluated lamp may be a fresh copy of
            # the original (see _sync_lamp): give it its values again (no images).
            try:
                _sync_lamp(lamp, current_lamp(module, request, settings), depsgraph)
            except ValueError as error:
                raise UserError(str(error)) from None
        return outcome
    refuse_if_not_editable(world)  # before anything is changed
    if clouds and live and not force:
        # The UI's timer computes a cloudy sky beside the interface instead (background.py).
        settings.status = (
            "the sky has clouds: press Update Sky to recompute it (seconds); renders update it every frame"
        )
        return outcome
    try:
        scene_json = (
            cloudy_scene_json(scene, settings, request, clouds, module, depsgraph) if clouds else None
        )
        result = sky_compute.compute(
            module,
            request,
            disc=settings.show_sun_disc,
            scene_json=scene_json,
            shadow_json=shadow_scene_json(scene, settings, request, clouds, module),
            progress=progress,
            **shadow_options(scene, module),
        )
    except (ValueError, OSError) as error:
        raise UserError(str(error)) from None
    apply_sky(scene, request, lamp, key, result, outcome, pack=pack, depsgraph=depsgraph, cloudy=bool(clouds))
    return outcome


def apply_sky(scene, request, lamp, key, result, outcome, *, pack, depsgraph=None, cloudy=False):
    """Writes a computed sky (sky_compute.SkyResult for `request`, whose sky_key is `key`)
    into the scene's world: images, nodes, the lamp, the status line. Main thread only."""
    settings = scene.world.welkin
    outcome.warnings += result.warnings
    height = request.width // 2
    sky = images.ensure(settings, "sky", request.width, height, request.color_space)
    images.write(sky, result.sky)
    if pack:
        images.pack(sky)
    world_nodes.install(scene.world, settings, sky, result.disc, result.moon_disc)
    images.drop_disc_image(settings)  # files from before the disc was drawn by nodes
    clouds = scene.world.welkin_clouds
    clouds.lamp_transmittance = result.lamp_transmittance
    render_graph = depsgraph is not None and depsgraph.mode == "RENDER"
    if result.shadow_map is not None:
        if not cloud_shadows.install(
            scene,
            result.shadow_map,
            request.sun_direction,
            clouds.shadow_extent_m,
            clouds.shadow_height_m,
            create=not render_graph,
        ):
            outcome.warnings.append(
                "Ground Shadows: the shadow layer is made by Update Sky "
                "(not during a render): press Update Sky, then render"
            )
    elif not render_graph:
        cloud_shadows.remove(scene.world)
    if settings.sync_lamp:
        _sync_lamp(lamp, result.lamp, depsgraph)
    settings.active = True
    settings.last_key = key
    outcome.updated = True
    outcome.seconds = result.seconds
    outcome.method = result.method
    settings.warnings = "\n".join(outcome.warnings)
    settings.status = (
        f"sky {request.width}x{height}{' with clouds' if cloudy else ''} by "
        f"{result.method} in "
        f"{result.seconds:.2f} s from '{lamp.name}'"
        + (
            f"; sun lamp x {result.lamp_transmittance:.3g} under the clouds"
            if result.lamp_transmittance < 1.0
            else ""
        )
        + (f"; {len(outcome.warnings)} warning(s)" if outcome.warnings else "")
    )


def remove_sky(scene):
    """Takes the add-on's nodes and images out; the user's world comes back as it was."""
    world = scene.world
    if world is None or not world.welkin.active:
        raise UserError("no Welkin sky in this scene's world to remove")
    refuse_if_not_editable(world)
    settings = world.welkin
    world_nodes.remove(world, settings)
    images.remove(settings)
    cloud_shadows.remove(world)
    restore_lamps(scene)
    place_time.remove_moon(world)
    settings.active = False
    settings.last_key = ""
    settings.status = ""
    if world.get("welkin_created"):
        scene.world = None
        if world.users == 0:
            bpy.data.worlds.remove(world)


def restore_lamps(scene):
    """Gives the scene's sun lamps back the colour, strength and angle they had before
    Sync Lamp first changed them (exactly: the values were kept as they were read),
    unless the user changed the lamp since Sync Lamp last did (Sync Lamp off): then the
    user's values stay."""
    for obj in scene.objects:
        data = obj.data if obj.type == "LIGHT" else None
        if data is None or LAMP_KEY not in data or data.library is not None:
            continue
        synced = data.get(SYNCED_KEY)
        if synced is None or list(synced) == _lamp_values(data):
            r, g, b, energy, angle = data[LAMP_KEY]
            data.color = (r, g, b)
            data.energy = energy
            if hasattr(data, "angle"):
                data.angle = angle
        for key in (LAMP_KEY, SYNCED_KEY):
            if key in data:
                del data[key]
