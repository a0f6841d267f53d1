# SPDX-License-Identifier: Apache-2.0
"""Run by test_viewport_window.py inside a windowed Blender (Xvfb, Mesa llvmpipe):
    xvfb-run -a blender --factory-startup --python-use-system-env --python THIS
with $WELKIN_VIEWPORT_RESULT the JSON file to write. Not a test_* file: it needs a window.

The factory 3D viewport is switched to Rendered shading with the Welkin engine; a timer
tags redraws (area.tag_redraw; Blender's main loop draws) until the preview's last level is drawn,
for a free perspective view, an orthographic one, the camera view, and a view changed
while a preview runs. Checked for each (viewport_preview.LAST):
  * view_draw ran and drew the region's full-size level, finite and non-negative;
  * its pixels equal the core's plate (welkin.camera_plate) for the camera
    viewport.camera_from_view makes from the region's matrices, with the scene as F12
    sees it (render_engine.scene_world): the same inputs, so exactly (0 difference);
  * the viewport's framebuffer after the draw, read back at the centre, holds those
    pixels (to half-float precision, 2e-3 relative: Blender's viewport buffer is
    RGBA16F, scene-linear; the view transform is applied after the engine draws);
  * camera view: the preview's rays inside the camera frame are the F12 camera's rays
    (within 1e-6 rad) at the same place in the frame;
  * a view changed mid-preview cancels the old job, and the final image is the new view's.
The draw latency (the longest view_draw, and the texture uploads) and the levels' times
are written to the result, not asserted (speed is measured, not tested).
"""

import json
import math
import os
import pathlib
import sys
import time
import traceback

import bpy
import numpy as np
from mathutils import Euler, Vector

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

RESULT = pathlib.Path(os.environ["WELKIN_VIEWPORT_RESULT"])
TIMEOUT_S = 240.0
failures, notes = [], {}


def finish():
    RESULT.write_text(json.dumps({"failures": failures, "notes": notes}, indent=1))
    sys.stdout.flush()
    os._exit(0)


def expect(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message, flush=True)


try:
    addon, native = t.install_addon()
    from welkin import plate, viewport  # noqa: E402
    from welkin.blender.engine import render_engine, viewport as vp  # noqa: E402

    scene, sun = t.new_scene(sun_elevation_deg=12, sun_azimuth_deg=40, camera_z=2.0)
    scene.render.engine = "WELKIN"
    scene.render.resolution_x, scene.render.resolution_y = 320, 180
    cam = scene.camera
    cam.rotation_euler = (math.radians(85), 0.0, math.radians(-60))
    cam.data.shift_x = 0.1
    win = bpy.context.window_manager.windows[0]
    area = max((a for a in win.screen.areas if a.type == "VIEW_3D"), key=lambda a: a.width * a.height)
    region = next(r for r in area.regions if r.type == "WINDOW")
    space = area.spaces.active
    space.shading.type = "RENDERED"
    rv3d = space.region_3d
    space.overlay.show_overlays = False  # the readback sees the engine's pixels only
    space.show_gizmo = False
except Exception:
    failures.append(traceback.format_exc())
    finish()


def set_view(kind):
    if kind == "CAMERA":
        rv3d.view_perspective = "CAMERA"
        return
    rv3d.view_perspective = kind
    rv3d.view_rotation = Euler((math.radians(80), 0.0, math.radians(-50))).to_quaternion()
    rv3d.view_location = (0.0, 0.0, 3.0)
    rv3d.view_distance = 5.0 if kind == "PERSP" else 40.0


def core_plate(w, h):
    """The core's plate for the region's view at w x h (what the preview must show)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    world = render_engine.scene_world(scene, depsgraph, native)
    camera = viewport.camera_from_view(
        rv3d.view_matrix, rv3d.window_matrix, rv3d.is_perspective, w, h, scene.unit_settings.scale_length
    )
    text = plate.scene_json(camera=camera, resolution=(w, h, 100), **world)
    return native.camera_plate(text), native.SceneDescription.from_json_string(text)


def frame_rays_match():
    """Camera view: rays at points of the camera's frame, the preview's against F12's."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    f12 = native.SceneDescription.from_json_string(
        render_engine.scene_description_json(scene, depsgraph, native)
    )
    _plate, view = core_plate(region.width, region.height)
    corners = [cam.matrix_world @ v for v in cam.data.view_frame(scene=scene)]
    # view_frame: top-right, bottom-right, bottom-left, top-left; project to region pixels.
    px = []
    for c in corners:
        clip = rv3d.perspective_matrix @ Vector((c.x, c.y, c.z, 1.0))
        px.append(((clip.x / clip.w + 1) / 2 * region.width, (clip.y / clip.w + 1) / 2 * region.height))
    (x1, y1), (x0, y0) = px[0], px[2]
    worst = 0.0
    for fx, fy in [(0.5, 0.5), (0.1, 0.2), (0.9, 0.85), (0.3, 0.7)]:
        # Region pixel (x up from the bottom) -> the preview camera's screen (top first).
        x, y = x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)
        _o, d_view, _ = view.camera_ray(x / region.width, 1.0 - y / region.height)
        _o, d_f12, _ = f12.camera_ray(fx, 1.0 - fy)
        worst = max(worst, math.acos(min(1.0, float(np.dot(d_view, d_f12)))))
    notes["camera_view_worst_ray_angle_rad"] = worst
    notes["camera_frame_px"] = [x0, y0, x1, y1]
    expect(worst < 1e-6, f"camera view: preview rays differ from the F12 camera's by {worst:g} rad")


def check_final(kind):
    L = vp.LAST
    key, w, h, pixels = L["image"]
    expect(
        (w, h) == (region.width, region.height),
        f"{kind}: last level {w} x {h}, region {region.width} x {region.height}",
    )
    img = np.asarray(pixels, dtype=np.float32).reshape(h, w, 4)[::-1]  # top row first
    expect(np.isfinite(img).all() and (img >= 0).all(), f"{kind}: non-finite or negative pixels")
    expect(float(img[..., :3].max()) > 0.0, f"{kind}: a black preview")
    core, _ = core_plate(w, h)
    diff = float(np.abs(img[..., :3] - core["combined"]).max())
    notes[f"{kind}_max_abs_diff_to_core"] = diff
    expect(diff == 0.0, f"{kind}: preview differs from the core's plate by {diff:g}")
    if "readback" in L:
        x, y, bw, bh = vp.READBACK
        fb = np.asarray(L["readback"], dtype=np.float32).reshape(bh, bw, 4)
        ref = img[::-1][y : y + bh, x : x + bw]  # bottom row first, as the framebuffer
        rel = float((np.abs(fb[..., :3] - ref[..., :3]) / np.maximum(ref[..., :3], 1e-6)).max())
        notes[f"{kind}_framebuffer_rel_diff"] = rel
        notes[f"{kind}_framebuffer_sample"] = [fb[0, 0].tolist(), ref[0, 0].tolist()]
        expect(rel < 2e-3, f"{kind}: framebuffer differs from the preview's pixels by {rel:g}")
    draws = L["draw_seconds"]
    notes[f"{kind}_draws"] = len(draws)
    notes[f"{kind}_max_draw_s"] = max(d for d, _u in draws)
    notes[f"{kind}_max_upload_s"] = max(u for _d, u in draws)
    notes[f"{kind}_median_draw_s"] = float(np.median([d for d, _u in draws]))
    notes[f"{kind}_levels_s"] = L["timings"]


STEPS = ["PERSP", "ORTHO", "CAMERA", "CHANGE"]
state = {"step": 0, "t0": time.time(), "started": False, "old_job": None}


def tick():
    try:
        if state["step"] >= len(STEPS):
            finish()
        kind = STEPS[state["step"]]
        if not state["started"]:
            vp.LAST.clear()
            set_view("PERSP" if kind == "CHANGE" else kind)
            vp.READBACK = (region.width // 2 - 4, region.height // 2 - 4, 8, 8)
            state.update(started=True, t_step=time.time(), changed=False)
        # Redraws by Blender's own main loop: a Python context override around
        # wm.redraw_timer would make every context lookup of the draw read the override's
        # Python dict, which Blender 3.4 does without the GIL when another Python thread
        # (the preview's) holds it (BPY_context_member_get trusts PyC_IsInterpreterActive):
        # Blender crashed so, 1 run in 3. Users never draw under an override.
        area.tag_redraw()
        L = vp.LAST
        if kind == "CHANGE" and not state["changed"] and L.get("job") is not None:
            # Mid-preview: turn the view; the running job must be cancelled.
            state["old_job"] = L["job"]
            rv3d.view_rotation = Euler((math.radians(95), 0.0, math.radians(10))).to_quaternion()
            state["changed"] = True
            return 0.02
        current = L.get("job")
        if (
            current is not None
            and current.done
            and L.get("image") is not None
            and L["image"][0] == current.key
            and L["image"][1] == region.width
            and (kind != "CHANGE" or current is not state["old_job"])
        ):
            check_final(kind)
            if kind == "CAMERA":
                frame_rays_match()
            if kind == "CHANGE":
                old = state["old_job"]
                old.join(timeout=10)
                expect(old.cancelled and not old.is_alive(), "the old view's job was not cancelled")
                notes["old_job_levels_done"] = len(old.timings)
            notes[f"{kind}_seconds_to_final"] = time.time() - state["t_step"]
            state.update(step=state["step"] + 1, started=False)
        elif time.time() - state["t0"] > TIMEOUT_S:
            failures.append(
                f"{kind}: no final preview after {TIMEOUT_S} s; LAST = "
                f"{ {k: v for k, v in L.items() if k not in ('image', 'readback')} }"
            )
            finish()
        return 0.05
    except Exception:
        failures.append(traceback.format_exc())
        finish()


bpy.app.timers.register(tick, first_interval=0.5)
