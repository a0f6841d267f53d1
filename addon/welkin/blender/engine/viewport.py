# SPDX-License-Identifier: GPL-3.0-or-later
"""The Welkin engine's viewport preview (Rendered shading): the plate the F12 render makes
(sky, sun disc, clouds, aerial ground; render_engine.py), for the viewport's own view.

  view_update  reads the scene on the main thread (render_engine.scene_world: the same
               atmosphere, sun, clouds and ground as F12) and restarts the preview.
  view_draw    takes the view from the region (viewport.camera_from_view: the free
               view, or the camera view with the scene camera's frame), restarts the
               preview when it changed, and draws the newest finished image with
               Blender's gpu module: a float GPUTexture drawn under
               bind_display_space_shader (in Blender 3.x the IMAGE shader; the viewport
               applies the scene's view transform to it), so a draw only uploads pixels.
  Job          a background thread: per level of viewport.levels (1/8 of the region,
               then 1/4, 1/2, 1) a welkin.CameraPlateRenderer renders the plate in bands
               of viewport.BAND_ROWS rows (the core releases the GIL), stopping at the
               next band or progress report once cancelled (a new view, a scene edit,
               the engine freed). A main-thread timer polls it and tags a redraw when a
               level is done.

Needs only the GL context Blender already has for any viewport: no GPU compute.
LAST records what the newest draw showed (tests read it): the level's size, its pixels,
the key of the view, how long the draws took.
"""

import collections
import threading
import time
import weakref

import bpy

# Imported here, on the main thread, before any preview thread runs: a first import of
# Blender's gpu module inside view_draw while a preview thread ran crashed Blender 3.4
# (SIGSEGV in PyType_Ready under the import, seen under Xvfb).
import gpu
import numpy as np
from gpu_extras.presets import draw_texture_2d

from ... import native as native_module
from ... import plate, viewport
from ..sky import update
from ..sky.scene_sun import UserError

# The newest preview drawn (tests/blender/viewport_window_script.py reads it), and, when
# READBACK is a (x, y, width, height) box of region pixels, the viewport's framebuffer
# there after the draw (LAST["readback"], RGBA rows bottom first).
LAST = {}
READBACK = None
POLL_S = 0.05
DRAW_HISTORY = 500  # draws whose timings are kept (a long session draws without end)


class Job(threading.Thread):
    """Renders the levels of one view of one scene state; `image` is the newest finished
    level: (key, width, height, RGBA float32 (h * w * 4), bottom row first)."""

    def __init__(self, native, world, cameras, key):
        super().__init__(daemon=True, name="welkin-viewport-preview")
        self.native, self.world, self.cameras, self.key = native, world, cameras, key
        self.cancelled = False
        self.image = None
        self.error = None
        self.fresh = False
        self.done = False
        self.timings = []  # (level size, seconds)

    def cancel(self):
        self.cancelled = True

    def run(self):
        try:
            for (w, h), camera in self.cameras:
                if self.cancelled:
                    return
                t0 = time.perf_counter()
                text = plate.scene_json(camera=camera, resolution=(w, h, 100), **self.world)
                renderer = self.native.CameraPlateRenderer(text)
                rgba = np.ones((h, w, 4), dtype=np.float32)
                for r0 in range(0, h, viewport.BAND_ROWS):
                    if self.cancelled:
                        return
                    r1 = min(h, r0 + viewport.BAND_ROWS)
                    band = renderer.render(rows=(r0, r1), progress=lambda f: not self.cancelled)
                    rgba[r0:r1, :, :3] = band["combined"]
                self.timings.append(((w, h), time.perf_counter() - t0))
                self.image = (self.key, w, h, np.ascontiguousarray(rgba[::-1]).reshape(-1))
                self.fresh = True
        except KeyboardInterrupt:
            return  # cancelled inside the core
        except (ValueError, OSError, RuntimeError) as error:
            self.error = str(error)
            self.fresh = True
        finally:
            self.done = True


class Preview:
    """One viewport's preview (the engine instance owns one)."""

    def __init__(self, engine, scene_world):
        self.engine = weakref.ref(engine)
        self.scene_world = scene_world  # render_engine.scene_world
        self.world = None  # render_engine.scene_world's dict, or None
        self.error = None  # a UserError's text from view_update
        self.generation = 0  # bumped by each view_update
        self.job = None
        self.texture = None
        self.texture_key = None
        self.drawn_size = None
        self.draw_seconds = collections.deque(maxlen=DRAW_HISTORY)  # (draw, upload) s, the newest
        self.timer = None

    # --- main thread -------------------------------------------------------------------
    def update(self, context, depsgraph):
        self.generation += 1
        try:
            native = update.module_or_error()
            self.world = self.scene_world(depsgraph.scene, depsgraph, native)
            self.error = None
        except (UserError, ValueError) as error:
            self.world, self.error = None, f"Welkin: {error}"
        self.stop()

    def view_key(self, context):
        region, rv3d = context.region, context.region_data
        return (
            self.generation,
            region.width,
            region.height,
            rv3d.is_perspective,
            tuple(tuple(r) for r in rv3d.view_matrix),
            tuple(tuple(r) for r in rv3d.window_matrix),
        )

    def start(self, context, key):
        region, rv3d = context.region, context.region_data
        scale = context.scene.unit_settings.scale_length
        cameras = []
        for w, h in viewport.levels(region.width, region.height):
            cameras.append(
                (
                    (w, h),
                    viewport.camera_from_view(
                        rv3d.view_matrix, rv3d.window_matrix, rv3d.is_perspective, w, h, scale
                    ),
                )
            )
        self.job = Job(native_module.module(), self.world, cameras, key)
        self.job.start()
        if self.timer is None:
            self.timer = self._poll
            bpy.app.timers.register(self.timer, first_interval=POLL_S)

    def stop(self):
        if self.job is not None:
            self.job.cancel()
            self.job = None

    def _poll(self):
        engine = self.engine()
        job = self.job
        if engine is None or job is None:
            self.timer = None
            return None
        if job.fresh:
            job.fresh = False
            try:
                engine.tag_redraw()
            except ReferenceError:  # the engine is gone
                self.stop()
                self.timer = None
                return None
        if job.done and not job.fresh:
            self.timer = None
            return None
        return POLL_S

    def draw(self, engine, context, depsgraph):
        t0 = time.perf_counter()
        if self.world is None:
            engine.update_stats("", self.error or "Welkin: no scene (view_update has not run)")
            return
        key = self.view_key(context)
        if self.job is None or self.job.key != key:
            self.stop()
            self.start(context, key)
        job = self.job
        if job.error:
            engine.update_stats("", f"Welkin: {job.error}")
        elif job.image is not None:
            _key, w, h, _pixels = job.image
            state = "done" if job.done else "refining"
            engine.update_stats("", f"Welkin preview {w} x {h} ({state})")
        else:
            engine.update_stats("", "Welkin preview: rendering")
        upload = 0.0
        if job.image is not None and (self.texture_key is not job.image):
            upload = time.perf_counter()
            self._upload(job.image)
            upload = time.perf_counter() - upload
        if self.texture is not None:
            self._draw_texture(engine, context)
        self.draw_seconds.append((time.perf_counter() - t0, upload))
        LAST.update(
            key=key,
            image=self.texture_key,
            job=job,
            done=job.done,
            timings=list(job.timings),
            draw_seconds=list(self.draw_seconds),
            drawn_size=self.drawn_size,
            error=job.error,
        )
        if READBACK is not None and self.texture is not None:
            x, y, w, h = READBACK
            fb = gpu.state.active_framebuffer_get()
            LAST["readback"] = fb.read_color(x, y, w, h, 4, 0, "FLOAT").to_list()

    def _upload(self, image):
        _key, w, h, pixels = image
        buffer = gpu.types.Buffer("FLOAT", len(pixels), pixels)
        self.texture = gpu.types.GPUTexture((w, h), format="RGBA32F", data=buffer)
        self.texture_key = image

    def _draw_texture(self, engine, context):
        _key, w, h, _pixels = self.texture_key
        dw, dh = viewport.drawn_size(context.region.width, w, h)
        self.drawn_size = (dw, dh)
        gpu.state.blend_set("ALPHA_PREMULT")
        engine.bind_display_space_shader(context.scene)
        draw_texture_2d(self.texture, (0, 0), dw, dh)
        engine.unbind_display_space_shader()
        gpu.state.blend_set("NONE")
