# SPDX-License-Identifier: GPL-3.0-or-later
"""The scene's clouds as the scene JSON's "clouds" section: the world's enabled procedural
layers and every Volume object marked as a Welkin cloud (Object.welkin_cloud), with the VDB
file it shows at the frame (Blender's sequence rule, cloud_export.volume_file), its
matrix_world (as evaluated in the depsgraph when given: animated volumes) and grid.

A marked volume whose file for the frame is missing raises UserError naming the object and
the path, before anything is written; a volume whose sequence shows nothing at this frame
(CLIP outside its range) or that is hidden from renders is left out, as Blender leaves it
out of its own render.
"""

import bpy

from ... import cloud_export
from .. import compat
from ..sky.scene_sun import UserError


def marked_volumes(scene):
    """The scene's Volume objects marked as Welkin clouds, by name."""
    return sorted(
        (o for o in scene.objects if o.type == "VOLUME" and o.welkin_cloud.enabled), key=lambda o: o.name
    )


def volume_path(volume, frame):
    """The absolute path of the VDB file `volume` (a Volume datablock) shows at `frame`,
    or None where its sequence shows nothing."""
    path = bpy.path.abspath(volume.filepath, library=volume.library)
    return cloud_export.volume_file(
        path,
        volume.is_sequence,
        frame,
        volume.frame_start,
        volume.frame_offset,
        volume.frame_duration,
        volume.sequence_mode,
    )


def has_clouds(scene, volumes=True):
    """True when the scene has an enabled cloud layer, or (`volumes`) a marked volume."""
    world = scene.world
    layers = world is not None and any(l.enabled for l in world.welkin_clouds.layers)
    return layers or (volumes and bool(marked_volumes(scene)))


def volumes_in_world(scene):
    """Whether the world's sky texture holds the marked volumes too (WelkinCloudSettings.
    volumes_in_world; off by default: Cycles and EEVEE render a volume object themselves,
    and a world that also held it would show it twice)."""
    world = scene.world
    return world is not None and world.welkin_clouds.volumes_in_world


def evaluated(id_, depsgraph):
    """`id_` as `depsgraph` evaluated it (its animated values at that depsgraph's frame),
    or `id_` itself without a depsgraph.

    A render's depsgraph (`blender -a`, F12, Ctrl F12) is not the active one: Blender
    animates its own evaluated copies of the world and the objects and leaves the
    originals at the values of the frame the interface shows (only the active depsgraph
    writes animated values back). Reading the original world's cloud layers during such a
    render gives every frame the clouds of that one frame: the keyed wind offset stands
    still. So the values come from the evaluated copy whenever a depsgraph is given."""
    if depsgraph is None or id_ is None:
        return id_
    return id_.evaluated_get(depsgraph)


def clouds_section(scene, depsgraph=None, frame=None, with_volumes=True):
    """The "clouds" dict for the scene at `frame` (default: the current frame), or None
    for a clear sky: the values `depsgraph` evaluated for that frame when given (keyed
    wind, coverage, density...), else the originals'; `with_volumes`: with the marked volumes.
    UserError for a marked volume without a file, more than MAX_LAYERS enabled layers, or a
    layer number that is not finite."""
    world = evaluated(scene.world, depsgraph)
    frame = scene.frame_current if frame is None else frame
    settings = world.welkin_clouds if world is not None else None
    layers = []
    if settings is not None:
        enabled = [layer for layer in settings.layers if layer.enabled]
        if len(enabled) > cloud_export.MAX_LAYERS:
            raise UserError(
                f"World > Welkin Clouds has {len(enabled)} enabled cloud layers; "
                f"Welkin renders at most {cloud_export.MAX_LAYERS}: disable or "
                f"remove some"
            )
        for layer in enabled:
            values = {k: getattr(layer, k) for k in cloud_export.LAYER_FIELDS}
            try:
                layers.append(cloud_export.layer_dict(values, layer.seed, layer.wind_offset_m))
            except ValueError as error:
                raise UserError(f"cloud layer '{layer.name}': {error}") from None
    volumes = []
    for ob in marked_volumes(scene) if with_volumes else ():
        ob_eval = evaluated(ob, depsgraph)
        if ob_eval.hide_render:
            continue
        volume = ob.data
        if not volume.filepath:
            raise UserError(
                f"volume object '{ob.name}' is marked as a Welkin cloud but has no "
                f"VDB file (Object Data > OpenVDB File)"
            )
        path = volume_path(volume, frame)
        if path is None:
            continue
        try:
            volumes.append(
                cloud_export.volume_dict(
                    ob.name,
                    path,
                    ob_eval.welkin_cloud.grid or "density",
                    [list(r) for r in ob_eval.matrix_world],
                    ob_eval.welkin_cloud.density_scale,
                    scene.unit_settings.scale_length,
                    compat.cycles_vdb_placement(),
                )
            )
        except cloud_export.MissingVolume as error:
            raise UserError(str(error)) from None
    if settings is None:
        albedo, lighting = 1.0, {"max_steps": 96, "light_steps": 8, "ambient_steps": 4, "octaves": 4}
    else:
        albedo = settings.albedo
        lighting = {k: getattr(settings, k) for k in cloud_export.LIGHTING_FIELDS}
    return cloud_export.clouds_dict(layers, volumes, albedo, lighting)


# The clouds of the frame being rendered, read at frame_change_post: (scene name, frame,
# the render depsgraph's address) -> the "clouds" dict, one entry at most.
_captured = {}


def _capture_key(scene, depsgraph):
    return (scene.name, scene.frame_current, depsgraph.as_pointer())


def capture(scene, depsgraph):
    """frame_change_post of a render: keeps this frame's clouds for the render engine.

    Blender evaluates a render's depsgraph again after frame_change_post when a handler
    changed data (the sky update writes the world's images and state); that second pass
    copies the world from the original without animating it again, so by the time the
    engine's render() runs, the evaluated world holds the original's (the interface's
    frame's) values: a keyed wind offset would stand still. Read here, before anything
    is written, the values are this frame's."""
    _captured.clear()
    if depsgraph is None or depsgraph.mode != "RENDER":
        return
    try:
        _captured[_capture_key(scene, depsgraph)] = clouds_section(scene, depsgraph)
    except UserError:
        pass  # the engine reads them itself, and reports the problem


def frame_clouds(scene, depsgraph):
    """The clouds of the frame `depsgraph` renders: those capture() kept for it, else read
    now (clouds_section)."""
    if depsgraph is not None and depsgraph.mode == "RENDER":
        key = _capture_key(scene, depsgraph)
        if key in _captured:
            return _captured[key]
    return clouds_section(scene, depsgraph)
