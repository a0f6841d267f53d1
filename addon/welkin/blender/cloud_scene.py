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

from .. import cloud_export
from . import compat
from .scene_sun import UserError


def marked_volumes(scene):
    """The scene's Volume objects marked as Welkin clouds, by name."""
    return sorted((o for o in scene.objects
                   if o.type == 'VOLUME' and o.welkin_cloud.enabled), key=lambda o: o.name)


def volume_path(volume, frame):
    """The absolute path of the VDB file `volume` (a Volume datablock) shows at `frame`,
    or None where its sequence shows nothing."""
    path = bpy.path.abspath(volume.filepath, library=volume.library)
    return cloud_export.volume_file(path, volume.is_sequence, frame, volume.frame_start,
                                    volume.frame_offset, volume.frame_duration,
                                    volume.sequence_mode)


def has_clouds(scene):
    world = scene.world
    layers = world is not None and any(l.enabled for l in world.welkin_clouds.layers)
    return layers or bool(marked_volumes(scene))


def clouds_section(scene, depsgraph=None, frame=None):
    """The "clouds" dict for the scene at `frame` (default: the current frame), or None
    for a clear sky. UserError for a marked volume without a file."""
    world = scene.world
    frame = scene.frame_current if frame is None else frame
    settings = world.welkin_clouds if world is not None else None
    layers = []
    if settings is not None:
        for layer in settings.layers:
            if layer.enabled:
                values = {k: getattr(layer, k) for k in cloud_export.LAYER_FIELDS}
                layers.append(cloud_export.layer_dict(values, layer.seed, layer.wind_offset_m))
    volumes = []
    for ob in marked_volumes(scene):
        evaluated = ob.evaluated_get(depsgraph) if depsgraph is not None else ob
        if evaluated.hide_render:
            continue
        volume = ob.data
        if not volume.filepath:
            raise UserError(f"volume object '{ob.name}' is marked as a Welkin cloud but has no "
                            f"VDB file (Object Data > OpenVDB File)")
        path = volume_path(volume, frame)
        if path is None:
            continue
        try:
            volumes.append(cloud_export.volume_dict(
                ob.name, path, ob.welkin_cloud.grid or "density",
                [list(r) for r in evaluated.matrix_world], ob.welkin_cloud.density_scale,
                scene.unit_settings.scale_length, compat.cycles_vdb_placement()))
        except cloud_export.MissingVolume as error:
            raise UserError(str(error)) from None
    if settings is None:
        albedo, lighting = 1.0, {"max_steps": 96, "light_steps": 8, "ambient_steps": 4,
                                 "octaves": 4}
    else:
        albedo = settings.albedo
        lighting = {k: getattr(settings, k) for k in cloud_export.LIGHTING_FIELDS}
    return cloud_export.clouds_dict(layers, volumes, albedo, lighting)
