# SPDX-License-Identifier: GPL-3.0-or-later
"""The sky follows the lamp.

  * In the UI, depsgraph_update_post notices that the sky's request changed (the sun lamp
    turned, a setting changed) and arms a timer; the update runs once the changes have
    stopped for DEBOUNCE_S, so dragging a lamp recomputes a few times, not per event. A
    clear sky is recomputed there and then (a fraction of a second); a cloudy one (seconds)
    beside the interface, with its progress in the status line (background.py).
  * In animation (playback, and `blender -b file.blend -a` renders, where no timer or UI
    runs), frame_change_post updates the sky synchronously from the depsgraph it is given
    (the render's own one during renders): the lamp's evaluated transform at that frame.
    Blender evaluates that depsgraph again when a frame_change_post handler changed data,
    so the lamp's new strength and the new image reach the frame being rendered.
    frame_change_pre only drops a pending UI timer and cancels a background sky (the
    frame's own update follows).
  * save_pre packs images that changed since they were last packed, so the saved file
    carries the sky it shows (the add-on's images of local worlds only).
All are @persistent (they stay across file loads) and need no UI. Failures are printed and
kept in the panel's status line (a linked world's status cannot be written: printed only);
a handler never raises. In a command-line render (`blender -b file.blend -a`), a frame
whose sky could not be updated fails (farm.py): not written, non-zero exit.
"""

import threading
import time

import bpy
from bpy.app.handlers import persistent

from .sky import background, place_time, scene_sun, update
from .clouds import scene as cloud_scene, shadows as cloud_shadows
from . import farm, farm_bake
from .sky.scene_sun import UserError

DEBOUNCE_S = 0.15
_state = {"due": 0.0, "armed": False}


def _headless():
    """True in `blender -b` (no timers run there). A function, so a headless test can
    stand in for the UI."""
    return bpy.app.background


def _log(settings, text):
    print(f"Welkin: {text}")
    if settings is not None and update.not_editable(settings.id_data) is None:
        settings.status = text


def _live(scene):
    world = scene.world
    return world is not None and world.welkin.active and world.welkin.auto_update


def _guarded(scene, action):
    """Runs action(); a failure goes to the status line, since a handler or a timer must
    never break Blender's loop. Returns the failure's text, or None."""
    try:
        action()
    except UserError as error:
        text = f"sky not updated: {error}"
    except Exception as error:
        text = f"sky not updated: unexpected {type(error).__name__}: {error}"
    else:
        return None
    _log(scene.world.welkin, text)
    return text


def _run(scene, depsgraph, *, pack, live=False):
    def update_now():
        outcome = update.update_sky(scene, depsgraph, pack=pack, live=live)
        for warning in outcome.warnings if outcome.updated else ():
            print(f"Welkin: warning: {warning}")

    return _guarded(scene, update_now)


def _tick():
    wait = _state["due"] - time.monotonic()
    if wait > 0.0:
        return wait
    _state["armed"] = False
    scene = bpy.context.scene
    if scene is not None and _live(scene):
        if cloud_scene.has_clouds(scene, volumes=cloud_scene.volumes_in_world(scene)):
            _guarded(scene, lambda: (place_time.place_now(scene), background.start(scene)))
        else:
            background.cancel()  # the clouds were switched off while a cloudy sky computed
            _run(scene, None, pack=False, live=True)
    return None


def _arm():
    _state["due"] = time.monotonic() + DEBOUNCE_S
    if not _state["armed"]:
        _state["armed"] = True
        bpy.app.timers.register(_tick, first_interval=DEBOUNCE_S)


def _disarm():
    if _state["armed"] and bpy.app.timers.is_registered(_tick):
        bpy.app.timers.unregister(_tick)
    _state["armed"] = False


def _stale(scene, depsgraph):
    settings = scene.world.welkin
    if farm_bake.check_frame(scene) == "":
        return False  # the farm bake shows this frame (Update Sky would drop it)
    try:
        request, _lamp, _warnings = scene_sun.request_for(scene, settings, depsgraph)
        clouds = update.clouds_of(scene, depsgraph)
    except UserError:
        return False
    key = update.sky_key(settings, request, clouds)
    # Not stale while a background job computes this very state (its own status updates
    # come back here as depsgraph updates of the world).
    return key != settings.last_key and key != background.pending_key()


def settings_changed(settings, context):
    """A panel parameter changed (property update callback)."""
    if _headless() or not settings.active or not settings.auto_update:
        return
    _arm()


@persistent
def on_depsgraph_update(scene, depsgraph=None):
    # Headless sessions have no timers: scripts call update_sky, renders get frame changes.
    if _headless() or not _live(scene):
        return
    if depsgraph is not None and not any(_concerns_sky(u.id) for u in depsgraph.updates):
        return  # a cheap filter: most edits touch neither a sun lamp nor the camera
    if _stale(scene, None):
        _arm()


def _concerns_sky(id_):
    if isinstance(id_, bpy.types.Object):
        return id_.type == "CAMERA" or (id_.type == "LIGHT" and id_.data.type == "SUN")
    return isinstance(id_, (bpy.types.Scene, bpy.types.World, bpy.types.Light))


@persistent
def on_frame_change_pre(scene, depsgraph=None):
    _disarm()
    background.cancel()


@persistent
def on_frame_change_post(scene, depsgraph=None):
    cloud_scene.capture(scene, depsgraph)  # before anything is written (blender/clouds/scene.py)
    if not _live(scene):
        return
    if farm_bake.on_frame(scene, depsgraph, lambda text: _log(scene.world.welkin, text)):
        return  # the farm bake renders this frame (or refuses a stale one)
    # UI renders (F12, Ctrl F12) call frame handlers on the render thread while the
    # interface keeps drawing; changing images and lamps from there is only safe with
    # Render > Lock Interface on. Headless renders (-a) run on the main thread.
    if threading.current_thread() is not threading.main_thread() and not scene.render.use_lock_interface:
        _log(
            scene.world.welkin,
            "sky not updated for this frame: the render runs beside "
            "the interface; enable Render > Lock Interface so renders follow the sun lamp",
        )
        return
    failure = _run(scene, depsgraph, pack=False)
    if failure is not None and depsgraph is not None and depsgraph.mode == "RENDER":
        # This frame would render with the previous frame's sky: fail it (farm.py).
        farm.fail_frame(scene, failure)


@persistent
def on_save_pre(*_args):
    for world in bpy.data.worlds:
        if update.not_editable(world) is not None:
            continue  # a linked world's images live in its library
        settings = world.welkin
        shadow_maps = [i for i in bpy.data.images if i.get(cloud_shadows.SHADOW_KEY) == world.name_full]
        for image in (settings.sky_image, *shadow_maps):
            if image is not None and image.library is None and (image.is_dirty or image.packed_file is None):
                update.images.pack(image)


@persistent
def on_load_pre(*_args):
    background.stop()


@persistent
def on_load_post(*_args):
    _disarm()


_HANDLERS = (
    (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
    (bpy.app.handlers.frame_change_pre, on_frame_change_pre),
    (bpy.app.handlers.frame_change_post, on_frame_change_post),
    (bpy.app.handlers.save_pre, on_save_pre),
    (bpy.app.handlers.load_pre, on_load_pre),
    (bpy.app.handlers.load_post, on_load_post),
)


def register():
    for handlers, function in _HANDLERS:
        if function not in handlers:
            handlers.append(function)


def unregister():
    _disarm()
    background.stop()
    for handlers, function in reversed(_HANDLERS):
        if function in handlers:
            handlers.remove(function)
