"""Aerial perspective for camera renders (Scene.welkin_aerial, Properties > Render >
Welkin Aerial Perspective). Off by default.

On, it hazes the frame Blender renders itself, in Cycles and EEVEE (F12, `-f`, `-a`, any
`-o`, the Composite / Group Output node and File Output nodes): blender/aerial/frame.py adds a node
group to every material that samples the frame's aerial-perspective table and writes two
shader AOVs, and a compositor group that applies Image x T + Inscatter after the Render
Layers node. The table is baked for each frame's camera, sun and atmosphere in
frame_change_post, with the render's own depsgraph, before the frame renders (no frame of
delay). Disabling takes everything out again.

"Write pass files" (off by default) adds, as before, files beside each render from the
render's Z pass (scene_export.frame_path, from scene.render.filepath and the frame):
  welkin_scene_NNNN.json      the frame's SceneDescription (reproduces it with
                              `welkin aerial --scene ... --depth welkin_render_NNNN.exr
                              --depth-channel Depth.V`)
  welkin_aerial_NNNN.exr      Welkin.AerialInscatter.RGB, Welkin.AerialTransmittance.RGB
                              (and the cloud passes, clouds marched up to the geometry)
  welkin_composite_NNNN.exr   R G B: Image x Transmittance + Inscatter (and the clouds over
                              it; the render layer's Image, before the user's compositing)
A file that exists and was not written by the add-on is never replaced: the frame is
reported instead. Problems (no camera, a fisheye camera, no sun lamp, no Z pass) are
printed and shown in the panel's status line; a handler never raises. In a command-line
render (`blender -b file.blend -a`) such a frame fails (farm.py): Blender stops, the frame's
file is not left on disk, and the exit status is non-zero.
"""
import json
import math
import os

import bpy
from bpy.app.handlers import persistent

from ... import native, scene_export, sky_request
from . import compositor, frame as aerial_frame
from ..clouds import scene as cloud_scene
from .. import compat, farm
from ..sky import images, scene_sun
from ..sky.scene_sun import UserError


def _toggled(settings, context):
    scene = settings.id_data  # the Scene that owns these settings
    if settings.enabled:  # (Write Pass Files alone, with aerial perspective off, does nothing)
        enable(scene)
    else:
        disable(scene)


class WelkinAerialSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(
        name="Aerial Perspective", default=False, update=_toggled,
        description="Haze the rendered frame with Welkin's aerial perspective (adds a node "
                    "group to the materials, two shader AOVs and a compositor group)")
    side_files: bpy.props.BoolProperty(
        name="Write Pass Files", default=False, update=_toggled,
        description="Also write the passes (and the clouds marched up to the geometry), the "
                    "frame's scene JSON and the hazed frame beside every render, from the Z "
                    "pass (turns the Z pass on)")
    method: bpy.props.EnumProperty(
        name="Method", default='froxel',
        items=(('froxel', "Froxels", "Hillaire 2020 camera volume (fast)"),
               ('raymarch', "Ray march", "Every pixel marched (reference, slow)")))
    status: bpy.props.StringProperty(options={'HIDDEN'})
    nodes_installed: bpy.props.BoolProperty(options={'HIDDEN'})
    previous_use_pass_z: bpy.props.BoolProperty(options={'HIDDEN'})
    compositor_undo: bpy.props.StringProperty(options={'HIDDEN'})
    added_aovs: bpy.props.StringProperty(options={'HIDDEN'})


def _log(scene, text):
    print(f"Welkin: {text}")
    scene.welkin_aerial.status = text


def base_of(scene):
    return scene_export.file_base(bpy.path.abspath(scene.render.filepath))


def enable(scene):
    s = scene.welkin_aerial
    for warning in aerial_frame.install(scene, s):
        _log(scene, warning)
    try:
        bake(scene)
    except UserError as error:
        _log(scene, f"aerial perspective: {error}")
    if s.side_files:
        enable_side_files(scene)
    else:
        disable_side_files(scene)


def disable(scene):
    disable_side_files(scene)
    aerial_frame.remove(scene, scene.welkin_aerial)
    _baked.clear()


def bake(scene, depsgraph=None, text=None):
    """Bakes the frame's table (aerial_frame.bake) for the camera and sun as evaluated in
    `depsgraph` (or as they are now); raises UserError."""
    module = native.module()
    if module is None:
        raise UserError(native.message())
    if text is None:
        text = scene_json(scene, module, depsgraph)
    try:
        aerial_frame.bake(scene, module, text, scene.unit_settings.scale_length, _baked)
    except (ValueError, OSError) as error:
        raise UserError(str(error)) from None


# image name -> the key of what it holds (kept in Python, not in the file: a file loads with
# the image's pixels blank)
_baked = {}


def enable_side_files(scene):
    s = scene.welkin_aerial
    if not s.nodes_installed:
        s.previous_use_pass_z = all(layer.use_pass_z for layer in scene.view_layers)
    for layer in scene.view_layers:
        layer.use_pass_z = True
    for warning in compositor.install(scene, s, scene_export.file_output_base(base_of(scene))):
        _log(scene, warning)


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
    if cam.type == 'PANO':
        c = compat.camera_panorama(cam)
        if c is None:
            raise UserError("panoramic camera: its panorama settings need the Cycles add-on "
                            "(enabled by default)")
        if c.panorama_type != 'EQUIRECTANGULAR':
            raise UserError(f"camera '{ob.name}': panorama type {c.panorama_type} is not "
                            f"supported by aerial perspective (only EQUIRECTANGULAR)")
        panorama = dict(panorama_type=c.panorama_type,
                        latitude_min_deg=math.degrees(c.latitude_min),
                        latitude_max_deg=math.degrees(c.latitude_max),
                        longitude_min_deg=math.degrees(c.longitude_min),
                        longitude_max_deg=math.degrees(c.longitude_max))
    return scene_export.camera_dict(
        [list(r) for r in ob.matrix_world], cam.type, cam.lens, cam.sensor_width,
        cam.sensor_height, cam.sensor_fit, cam.ortho_scale, cam.shift_x, cam.shift_y,
        cam.clip_start, cam.clip_end, scale_length=scene.unit_settings.scale_length,
        panorama=panorama)


def scene_json(scene, module, depsgraph=None):
    """The frame's scene JSON text (validated by the core), from the world's Welkin sky
    settings, the sun lamp the sky uses, the scene camera and the render size; the camera
    and lamp as evaluated in `depsgraph` when given (the render's own, at its frame)."""
    if scene.world is None:
        raise UserError("the scene has no world: aerial perspective takes its atmosphere "
                        "from World > Welkin Sky")
    settings = scene.world.welkin
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, depsgraph)
    atmosphere = json.loads(sky_request.build_atmosphere(request, module).to_json_string())
    r = scene.render
    d = scene_export.scene_dict(
        atmosphere, settings.altitude_m, request.sun_direction, settings.exposure,
        sky_request.resolve_method(settings.method, module), camera_of(scene, depsgraph),
        (r.resolution_x, r.resolution_y, r.resolution_percentage),
        aerial={"method": scene.welkin_aerial.method},
        clouds=cloud_scene.clouds_section(scene, depsgraph), color_space=request.color_space)
    return module.SceneDescription.from_json_string(json.dumps(d)).to_json_string()


def _ours(module, path, kind):
    """True when `path` is absent or a file the add-on wrote (so it may be replaced)."""
    if not os.path.exists(path):
        return True
    try:
        if kind == "scene":
            module.SceneDescription.from_json(path)
            return True
        _pixels, names = module.read_exr(path)
    except Exception:
        return False
    if kind == "aerial":
        return sorted(names) in (sorted(scene_export.PASS_CHANNELS),
                                 sorted(scene_export.PASS_CHANNELS + scene_export.CLOUD_CHANNELS))
    return sorted(names) == sorted(scene_export.COMPOSITE_CHANNELS)


def write_frame(scene, frame):
    """Writes the frame's scene JSON, passes and composite; returns their paths."""
    import numpy as np
    module = native.module()
    if module is None:
        raise UserError(native.message())
    # Camera, sun and world first (the likelier faults), as the render's depsgraph had
    # them at this frame (frame_change_post), else as they are now.
    text = _at_frame.pop(scene.name, {}).get(frame)
    if text is None or scene.camera is None:
        text = scene_json(scene, module)
    if isinstance(text, UserError):
        raise text
    base = base_of(scene)
    paths = {k: scene_export.frame_path(base, k, frame) for k in ("scene", "aerial", "composite")}
    for kind, path in paths.items():
        if not _ours(module, path, kind):
            raise UserError(f"{path} exists and was not written by Welkin: not replaced "
                            f"(move it, or change Output > Output Path)")
    render_path = scene_export.frame_path(base, "render", frame)
    if not os.path.exists(render_path):
        raise UserError(f"the render's depth file {render_path} is missing: the compositor "
                        f"must run (Post Processing > Compositing on) with the node "
                        f"'{compositor.DEPTH_NODE}'; toggle Aerial Perspective off and on")
    desc = module.SceneDescription.from_json_string(text)
    pixels, names = module.read_exr(render_path)
    depth_name = next((n for n in names if n.startswith("Depth.")), None)
    if depth_name is None:
        raise UserError("the render has no Z pass (View Layer > Passes > Data > Z, linked "
                        f"to the '{compositor.DEPTH_NODE}' node): the pass is on from the "
                        "next render; toggle Aerial Perspective off and on to relink it")
    if not (pixels[..., names.index(depth_name)] > 0.0).any():
        # An unlinked File Output input writes a constant 0: the Z pass did not arrive.
        raise UserError("the render's Z pass is empty (View Layer > Passes > Data > Z off, "
                        "or its link to the 'Welkin Aerial Depth' node removed): it is on "
                        "from the next render; toggle Aerial Perspective off and on")
    image = np.stack([pixels[..., names.index(f"Image.{c}")] for c in "RGB"], axis=-1)
    depth = pixels[..., names.index(depth_name)] * np.float32(scene.unit_settings.scale_length)
    depth = np.ascontiguousarray(depth)
    clouds = None
    try:
        inscatter, transmittance = module.aerial_perspective(desc, depth)
        if "clouds" in json.loads(text):
            # Welkin.Clouds marched up to the render's depth (geometry in front hides it).
            passes = module.cloud_passes(desc, depth)
            clouds = np.asarray(passes["Welkin.Clouds"], dtype=np.float32)
            cloud_depth = np.asarray(passes["Welkin.CloudDepth"], dtype=np.float32)
    except (ValueError, OSError) as error:
        raise UserError(str(error)) from None
    layers, channels = [inscatter, transmittance], list(scene_export.PASS_CHANNELS)
    if clouds is not None:
        layers += [clouds, cloud_depth[..., None]]
        channels += list(scene_export.CLOUD_CHANNELS)
    desc.to_json(paths["scene"], overwrite=True)
    module.write_exr(paths["aerial"], np.concatenate(layers, axis=-1), channels, overwrite=True,
                     attributes=[("welkinScene", text)])
    module.write_exr(paths["composite"],
                     np.ascontiguousarray(scene_export.composite(image, inscatter, transmittance,
                                                                 clouds), dtype=np.float32),
                     list(scene_export.COMPOSITE_CHANNELS), overwrite=True)
    return paths


# scene name -> {frame: the frame's scene JSON text, or the UserError it raised}
_at_frame = {}


@persistent
def on_frame_change_post(scene, depsgraph=None):
    """Renders evaluate the frame in their own depsgraph and leave the original objects
    where they were: an animated camera or lamp is read here, where that depsgraph is
    handed over (in `-a`, `-f` and F12 alike), and used by render_post."""
    if depsgraph is None or not scene.welkin_aerial.enabled:
        return
    module = native.module()
    if module is None:
        return
    try:
        aerial_frame.install_materials()
        text = scene_json(scene, module, depsgraph)
        bake(scene, depsgraph, text)
    except UserError as error:
        text = error
    except Exception as error:
        text = UserError(f"unexpected {type(error).__name__}: {error}")
    _at_frame[scene.name] = {scene.frame_current: text}
    if isinstance(text, UserError) and depsgraph.mode == 'RENDER':
        # Known before the frame renders: fail it now, before anything is written.
        reason = f"aerial perspective not written for frame {scene.frame_current}: {text}"
        if not farm.fail_frame(scene, reason):
            _log(scene, reason)  # where the render cannot be stopped: said, at least


def _sync_output_path(scene):
    """Points the File Output node at the current output path. A render copies the
    compositor before its first render_pre, so the path is kept in step whenever the
    scene changes, when a file loads and when a render is initialised (render_init, before
    that copy: `blender -b file.blend -o PATH -f N` sets the output path after the file
    loaded, with no update of the scene), not only when a frame's render starts."""
    node = compositor.depth_node(scene)
    if node is not None:
        wanted = scene_export.file_output_base(base_of(scene))
        if compat.file_output_path(node) != wanted:  # a change recompiles the compositor
            compat.set_file_output_path(node, wanted)


@persistent
def on_depsgraph_update(scene, *_args):
    if scene.welkin_aerial.enabled and scene.welkin_aerial.side_files:
        _sync_output_path(scene)


@persistent
def on_load_post(*_args):
    _baked.clear()
    for scene in bpy.data.scenes:
        if scene.welkin_aerial.enabled and scene.welkin_aerial.side_files:
            _sync_output_path(scene)


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
    names = (aerial_frame.SCREEN_IMAGES if scene.render.engine == 'CYCLES'
             else (aerial_frame.IMAGE,))
    for name in names:
        image = bpy.data.images.get(name)
        if image is None or not image.get(aerial_frame.MARK) or image.library is not None:
            continue
        if image.packed_file is None or image.is_dirty:
            images.pack(image)
    return None


@persistent
def on_save_pre(*_args):
    for scene in bpy.data.scenes:
        if scene.library is not None:
            continue
        if scene.welkin_aerial.enabled:
            problem = pack_tables(scene)
            if problem is not None:
                _log(scene, problem)
        sky = scene.world is not None and scene.world.welkin.active
        if not (sky or scene.welkin_aerial.enabled):
            continue
        changing = farm.changing_inputs(scene)
        if changing:
            text = (f"saved for farms with the add-on only: {', '.join(changing)} "
                    f"animated; a Blender without Welkin would render every frame with "
                    f"frame {scene.frame_current}'s sky and haze")
            print(f"Welkin: warning: scene '{scene.name}': {text}")
            if scene.welkin_aerial.enabled:
                scene.welkin_aerial.status = text


@persistent
def on_render_init(scene, *_args):
    if scene.welkin_aerial.enabled and scene.welkin_aerial.side_files:
        _sync_output_path(scene)


@persistent
def on_render_pre(scene, *_args):
    farm.frame_started(scene)
    s = scene.welkin_aerial
    if not s.enabled:
        return
    try:
        for warning in aerial_frame.install(scene, s):
            _log(scene, warning)
        if not s.side_files:
            return
        z_on = all(layer.use_pass_z for layer in scene.view_layers)
        if not z_on:
            _log(scene, "the Z pass was off: turned on (takes effect from the next render)")
        node = compositor.depth_node(scene)
        wanted = scene_export.file_output_base(base_of(scene))
        # Touch the scene only when needed: UI renders call this beside the interface.
        if not z_on or node is None or compat.file_output_path(node) != wanted:
            enable_side_files(scene)  # the File Output node follows the output path
    except Exception as error:
        _log(scene, f"aerial perspective: unexpected {type(error).__name__}: {error}")


@persistent
def on_render_post(scene, *_args):
    if not (scene.welkin_aerial.enabled and scene.welkin_aerial.side_files):
        return
    frame = scene.frame_current
    try:
        paths = write_frame(scene, frame)
        _log(scene, f"aerial perspective of frame {frame}: {paths['aerial']}")
        return
    except UserError as error:
        text = f"aerial perspective not written for frame {frame}: {error}"
    except Exception as error:  # a handler must never break Blender's render loop
        text = (f"aerial perspective not written for frame {frame}: unexpected "
                f"{type(error).__name__}: {error}")
    _log(scene, text)
    # The frame's image is already saved (render_post follows the save): a command-line
    # render takes it away and stops, so the farm sees no file and a non-zero exit.
    farm.fail_frame(scene, text, remove_written=True)


class RENDER_PT_welkin_aerial(bpy.types.Panel):
    bl_label = "Welkin Aerial Perspective"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"

    def draw(self, context):
        s = context.scene.welkin_aerial
        layout = self.layout
        layout.use_property_split = True
        layout.prop(s, "enabled")
        col = layout.column()
        col.active = s.enabled
        col.prop(s, "side_files")
        row = col.row()
        row.active = s.side_files
        row.prop(s, "method")
        if s.status:
            layout.label(text=s.status, icon='INFO')


classes = (WelkinAerialSettings, RENDER_PT_welkin_aerial)
_HANDLERS = ((bpy.app.handlers.frame_change_post, on_frame_change_post),
             (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
             (bpy.app.handlers.load_post, on_load_post),
             (bpy.app.handlers.save_pre, on_save_pre),
             (bpy.app.handlers.render_init, on_render_init),
             (bpy.app.handlers.render_pre, on_render_pre),
             (bpy.app.handlers.render_post, on_render_post))


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.welkin_aerial = bpy.props.PointerProperty(type=WelkinAerialSettings)
    for handlers, function in _HANDLERS:
        if function not in handlers:
            handlers.append(function)


def unregister():
    for handlers, function in reversed(_HANDLERS):
        if function in handlers:
            handlers.remove(function)
    del bpy.types.Scene.welkin_aerial
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
