# SPDX-License-Identifier: GPL-3.0-or-later
"""Aerial perspective's handlers: the frame's table baked before each frame renders
(frame_change_post, with the render's own depsgraph), the compositor kept in step, the
pass files written after each render, and the tables packed when the file is saved; and
the feature's registration. A handler never raises: problems are printed, shown in the
panel and, in a command-line render, fail the frame (farm.py)."""

import bpy
from bpy.app.handlers import persistent

from ... import native, scene_export
from . import compositor, frame as aerial_frame, pass_files
from . import scene as aerial_scene
from .. import compat, farm, farm_bake
from ..sky.scene_sun import UserError
from .panel import RENDER_PT_welkin_aerial
from .properties import WelkinAerialSettings


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
    if farm_bake.on_frame(scene, depsgraph, lambda text: aerial_scene.log(scene, text)):
        # The farm bake renders this frame (or refuses a stale one); Write Pass Files
        # still reads the frame's scene JSON.
        pass_files.at_frame.pop(scene.name, None)
        if scene.welkin_aerial.side_files:
            try:
                text = aerial_scene.scene_json(scene, module, depsgraph)
            except UserError as error:
                text = error
            pass_files.at_frame[scene.name] = {scene.frame_current: text}
        return
    try:
        aerial_frame.install_materials()
        text = aerial_scene.scene_json(scene, module, depsgraph)
        aerial_scene.bake(scene, depsgraph, text)
    except UserError as error:
        text = error
    except Exception as error:
        text = UserError(f"unexpected {type(error).__name__}: {error}")
    pass_files.at_frame[scene.name] = {scene.frame_current: text}
    if isinstance(text, UserError) and depsgraph.mode == "RENDER":
        # Known before the frame renders: fail it now, before anything is written.
        reason = f"aerial perspective not written for frame {scene.frame_current}: {text}"
        if not farm.fail_frame(scene, reason):
            aerial_scene.log(scene, reason)  # where the render cannot be stopped: said, at least


@persistent
def on_depsgraph_update(scene, *_args):
    if scene.welkin_aerial.enabled and scene.welkin_aerial.side_files:
        pass_files.sync_output_path(scene)


@persistent
def on_load_post(*_args):
    farm.restore_cameras()
    aerial_scene.baked.clear()
    for scene in bpy.data.scenes:
        if scene.welkin_aerial.enabled and scene.welkin_aerial.side_files:
            pass_files.sync_output_path(scene)


@persistent
def on_save_pre(*_args):
    for scene in bpy.data.scenes:
        if scene.library is not None:
            continue
        baked = farm_bake.record(scene) is not None
        stale = baked and _bake_is_stale(scene)
        if not baked and scene.welkin_aerial.enabled:
            problem = aerial_scene.pack_tables(scene)
            if problem is not None:
                aerial_scene.log(scene, problem)
        sky = scene.world is not None and scene.world.welkin.active
        if not (sky or scene.welkin_aerial.enabled):
            continue
        changing = farm.changing_inputs(scene)
        hidden = farm.hide_camera(scene) if stale or (changing and not baked) else False
        if changing and not baked:
            text = f"saved for farms with the add-on only: {', '.join(changing)} animated; " + (
                "a Blender without Welkin refuses to render the file (no scene camera "
                "there); Bake for Farm makes it render there"
                if hidden
                else f"a Blender without Welkin would render every frame with frame "
                f"{scene.frame_current}'s sky and haze"
            )
            print(f"Welkin: warning: scene '{scene.name}': {text}")
            if scene.welkin_aerial.enabled:
                scene.welkin_aerial.status = text


def _bake_is_stale(scene):
    """A saved bake is checked frame by frame: a stale one is said (the add-on refuses its
    frames; the file is saved so that a Blender without it refuses it, farm.hide_camera).
    True when stale or when it could not be checked."""
    try:
        stale = farm_bake.verify(scene)
    except UserError as error:
        stale, problem = None, str(error)
    if stale == []:
        return False
    text = (
        f"Bake for Farm is stale for frames {farm_bake.plan.ranges(stale)}: press Bake for Farm "
        f"again; the add-on refuses these frames, a Blender without it the file (no scene "
        f"camera there)"
        if stale
        else f"Bake for Farm could not be checked: {problem}"
    )
    print(f"Welkin: warning: scene '{scene.name}': {text}")
    scene.welkin_aerial.status = text
    return True


@persistent
def on_save_post(*_args):
    farm.restore_cameras()


@persistent
def on_render_init(scene, *_args):
    farm.restore_cameras()  # the add-on enabled after the file loaded (`--addons`, a farm script)
    if scene.welkin_aerial.enabled and scene.welkin_aerial.side_files:
        pass_files.sync_output_path(scene)


@persistent
def on_render_pre(scene, *_args):
    farm.frame_started(scene)
    s = scene.welkin_aerial
    if not s.enabled:
        return
    try:
        for warning in aerial_frame.install(scene, s):
            aerial_scene.log(scene, warning)
        if not s.side_files:
            return
        z_on = all(layer.use_pass_z for layer in scene.view_layers)
        if not z_on:
            aerial_scene.log(scene, "the Z pass was off: turned on (takes effect from the next render)")
        node = compositor.depth_node(scene)
        wanted = scene_export.file_output_base(aerial_scene.base_of(scene))
        # Touch the scene only when needed: UI renders call this beside the interface.
        if not z_on or node is None or compat.file_output_path(node) != wanted:
            aerial_scene.enable_side_files(scene)  # the File Output node follows the output path
    except Exception as error:
        aerial_scene.log(scene, f"aerial perspective: unexpected {type(error).__name__}: {error}")


@persistent
def on_render_post(scene, *_args):
    if not (scene.welkin_aerial.enabled and scene.welkin_aerial.side_files):
        return
    frame = scene.frame_current
    try:
        paths = pass_files.write_frame(scene, frame)
        aerial_scene.log(scene, f"aerial perspective of frame {frame}: {paths['aerial']}")
        return
    except UserError as error:
        text = f"aerial perspective not written for frame {frame}: {error}"
    except Exception as error:  # a handler must never break Blender's render loop
        text = f"aerial perspective not written for frame {frame}: unexpected {type(error).__name__}: {error}"
    aerial_scene.log(scene, text)
    # The frame's image is already saved (render_post follows the save): a command-line
    # render takes it away and stops, so the farm sees no file and a non-zero exit.
    farm.fail_frame(scene, text, remove_written=True)


classes = (WelkinAerialSettings, RENDER_PT_welkin_aerial)
_HANDLERS = (
    (bpy.app.handlers.frame_change_post, on_frame_change_post),
    (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
    (bpy.app.handlers.load_post, on_load_post),
    (bpy.app.handlers.save_pre, on_save_pre),
    (bpy.app.handlers.save_post, on_save_post),
    (bpy.app.handlers.render_init, on_render_init),
    (bpy.app.handlers.render_pre, on_render_pre),
    (bpy.app.handlers.render_post, on_render_post),
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.welkin_aerial = bpy.props.PointerProperty(type=WelkinAerialSettings)
    for handlers, function in _HANDLERS:
        if function not in handlers:
            handlers.append(function)
    try:  # enabled after a file was loaded (`--addons`, a farm script): its cameras back
        farm.restore_cameras()
    except AttributeError:  # add-ons enabled at startup see no data yet (load_post does it)
        pass


def unregister():
    for handlers, function in reversed(_HANDLERS):
        if function in handlers:
            handlers.remove(function)
    del bpy.types.Scene.welkin_aerial
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
