# SPDX-License-Identifier: GPL-3.0-or-later
"""A cloudy sky for the live UI, computed beside the interface.

A cloudy world texture takes seconds (every pixel's ray is marched through the clouds): too
long to hold the interface at each nudge of the lamp. So when the debounced UI timer
(handlers.py) finds a cloudy sky stale:

  * start(), on the main thread, gathers everything that reads bpy: the sky request, its
    key, and the cloudy scene JSON (update.py);
  * a Python thread has the core render it (sky_compute.compute). The module releases the
    GIL while the core works, and the thread never touches bpy;
  * poll(), a bpy.app.timers function on the main thread, shows the job's progress in the
    panel's status line, and once it is done writes the images, nodes and lamp
    (update.apply_sky), unless the scene changed meanwhile (its sky key is not the job's
    any more): then the result is dropped and a job for the new state starts.

A quick preview comes first: for a world wider than PREVIEW_WIDTH the job computes the
same cloudy sky at PREVIEW_WIDTH (1/16 of the pixels at 1024 wide, so about 1/16 of the
time) before the full one, and poll() shows it as soon as it is there (status "preview
...; refining"), then replaces it with the full sky. The preview's key is not the full
sky's, so a preview is never taken for a current sky (a cancelled job leaves the world
stale, and the next change recomputes it).

A job is cancelled through its progress callback (it returns False and the core stops at
its next report, within a band of rows): by start() for a newer state, by a frame change
(the frame's own synchronous update follows), by loading a file and by unregistering.
Headless sessions run no timers; tests call poll() themselves.
"""

import dataclasses
import threading

import bpy

from ... import sky_compute
from . import scene_sun, update
from .scene_sun import UserError

POLL_S = 0.1
PREVIEW_WIDTH = 256
PREVIEW_SUFFIX = "|preview"  # on last_key while the world shows a preview


class Job:
    """One cloudy sky in the making. Only its own thread writes result / error."""

    def __init__(self, module, request, scene_json, disc, key, shadow_json=None, shadows=None):
        self.key = key
        self.cloudy = scene_json is not None
        self.fraction = 0.0
        self.cancelled = False
        self.result = None
        self.preview = None  # the preview's SkyResult, once computed
        self.preview_shown = False  # poll() applied it
        self.error = None
        self.done = threading.Event()
        self._args = (module, request, scene_json, disc, shadow_json, shadows or {})
        self.thread = threading.Thread(target=self._run, name="welkin-cloudy-sky", daemon=True)

    def _progress(self, fraction):
        self.fraction = fraction
        return not self.cancelled

    def preview_request(self):
        """The request of the preview, or None where the sky is no wider than it."""
        request = self._args[1]
        if not self.cloudy or request.width <= PREVIEW_WIDTH:
            return None
        return dataclasses.replace(request, width=PREVIEW_WIDTH)

    def _run(self):
        module, request, scene_json, disc, shadow_json, shadows = self._args
        try:
            preview = self.preview_request()
            if preview is not None:
                self.preview = sky_compute.compute(
                    module,
                    preview,
                    disc=disc,
                    scene_json=scene_json,
                    shadow_json=shadow_json,
                    progress=lambda f: self._progress(0.0),
                    **shadows,
                )
            self.result = sky_compute.compute(
                module,
                request,
                disc=disc,
                scene_json=scene_json,
                shadow_json=shadow_json,
                progress=self._progress,
                **shadows,
            )
        except KeyboardInterrupt:  # the progress callback said stop
            self.cancelled = True
        except Exception as error:  # reported by poll() on the main thread
            self.error = error
        finally:
            self.done.set()


_job = None


def current():
    """The running (not yet applied) job, or None."""
    return _job


def pending_key():
    """The sky key the running job computes, or None."""
    return _job.key if _job is not None and not _job.cancelled else None


def start(scene):
    """Starts computing `scene`'s cloudy sky beside the interface (main thread). Does nothing
    (returns False) when the sky is current or a job for the same state runs already.
    Raises UserError for what the user must fix (no sun lamp, a missing VDB file...)."""
    global _job
    module = update.module_or_error()
    settings = scene.world.welkin
    request, _lamp, _warnings = scene_sun.request_for(scene, settings, None)
    clouds = update.clouds_of(scene, None)
    key = update.sky_key(settings, request, clouds)
    if key == pending_key() or (
        key == settings.last_key and settings.sky_image is not None and update.images.owned(settings)
    ):
        return False
    update.refuse_if_not_editable(scene.world)  # a linked world: UserError, nothing changed
    cancel()
    scene_json = update.cloudy_scene_json(scene, settings, request, clouds, module, None) if clouds else None
    shadow_json = update.shadow_scene_json(scene, settings, request, clouds, module)
    _job = Job(
        module,
        request,
        scene_json,
        settings.show_sun_disc,
        key,
        shadow_json,
        update.shadow_options(scene, module),
    )
    _job.thread.start()
    settings.status = "computing the cloudy sky beside the interface: 0 %"
    if not bpy.app.timers.is_registered(poll):
        bpy.app.timers.register(poll, first_interval=POLL_S, persistent=False)
    return True


def poll():
    """Main-thread timer: the job's progress, then its result. Returns the seconds to the
    next call, or None when there is nothing left to wait for."""
    global _job
    job = _job
    if job is None:
        return None
    scene = bpy.context.scene
    settings = scene.world.welkin if scene is not None and scene.world is not None else None
    if not job.done.is_set():
        if settings is not None and not job.cancelled:
            if job.preview is not None and not job.preview_shown:
                _show_preview(scene, job)
            what = "refining" if job.preview_shown else "computing"
            settings.status = f"{what} the cloudy sky beside the interface: {100.0 * job.fraction:.0f} %"
            _redraw_properties()
        return POLL_S
    job.thread.join()
    _job = None
    if job.cancelled or settings is None:
        return None
    if job.error is not None:
        settings.status = f"sky not updated: {job.error}"
        return None
    try:
        request, lamp, warnings = scene_sun.request_for(scene, settings, None)
        key = update.sky_key(settings, request, update.clouds_of(scene, None))
        if key != job.key:  # the scene moved on while the job ran: its result is stale
            return POLL_S if start(scene) else None
        outcome = update.Outcome()
        outcome.warnings = warnings
        update.apply_sky(scene, request, lamp, key, job.result, outcome, pack=False, cloudy=job.cloudy)
    except UserError as error:
        settings.status = f"sky not updated: {error}"
    _redraw_properties()
    return None


def _show_preview(scene, job):
    """Writes the job's preview into the world (main thread), unless the scene moved on;
    the world's key says preview, so the sky stays stale until the full one is applied."""
    job.preview_shown = True
    settings = scene.world.welkin
    try:
        request, lamp, warnings = scene_sun.request_for(scene, settings, None)
        if update.sky_key(settings, request, update.clouds_of(scene, None)) != job.key:
            return
        outcome = update.Outcome()
        outcome.warnings = warnings
        preview = job.preview_request()
        update.apply_sky(
            scene, preview, lamp, job.key + PREVIEW_SUFFIX, job.preview, outcome, pack=False, cloudy=True
        )
    except UserError as error:
        settings.status = f"sky not updated: {error}"


def cancel():
    """Cancels the running job: its result is never applied. The timer ends by itself."""
    global _job
    if _job is not None:
        _job.cancelled = True
    _job = None


def stop(wait_s=5.0):
    """cancel(), the timer unregistered, and up to wait_s for the job's thread to end (on
    loading a file and unregistering the add-on)."""
    job = _job
    cancel()
    if bpy.app.timers.is_registered(poll):
        bpy.app.timers.unregister(poll)
    if job is not None:
        job.thread.join(wait_s)


def _redraw_properties():
    wm = bpy.context.window_manager
    for window in wm.windows if wm is not None else ():
        for area in window.screen.areas:
            if area.type == "PROPERTIES":
                area.tag_redraw()
