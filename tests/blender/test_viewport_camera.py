# SPDX-License-Identifier: Apache-2.0
"""The viewport preview's camera against F12's, headless: a viewport looking through the
scene camera has that camera's inverse as its view_matrix and its projection
(Object.calc_matrix_camera, Blender's own) as its window_matrix; viewport.camera_from_view
of those must be the F12 plate's camera: the same rays (within 1e-6 rad: the matrices are
float32) and the same low-resolution plate (within 1e-4 relative per pixel, of
max(value, 1e-3 x the image mean)), for a perspective camera with lens shift (sensor fit
AUTO), a portrait one fitted VERTICAL, and an orthographic one with shift.
"""

import math
import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

addon, native = t.install_addon()
from welkin import plate, viewport  # noqa: E402
from welkin.blender.engine import render_engine  # noqa: E402

scene, sun = t.new_scene(sun_elevation_deg=8, sun_azimuth_deg=20, camera_z=3.0)
scene.render.engine = "WELKIN"
cam = scene.camera
cam.rotation_euler = (math.radians(88), 0.0, math.radians(-70))

CASES = [
    (
        "persp-shift-auto",
        64,
        36,
        dict(type="PERSP", lens=28.0, shift_x=0.12, shift_y=-0.07, sensor_fit="AUTO"),
    ),
    (
        "persp-vertical-portrait",
        30,
        54,
        dict(type="PERSP", lens=40.0, shift_x=-0.05, shift_y=0.1, sensor_fit="VERTICAL", sensor_height=24.0),
    ),
    (
        "ortho-shift",
        48,
        32,
        dict(type="ORTHO", ortho_scale=30.0, shift_x=0.2, shift_y=0.05, sensor_fit="AUTO"),
    ),
]
for name, w, h, settings in CASES:
    for key, value in settings.items():
        setattr(cam.data, key, value)
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    bpy.context.view_layer.update()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = cam.evaluated_get(depsgraph)
    window = evaluated.calc_matrix_camera(depsgraph, x=w, y=h)
    view = evaluated.matrix_world.inverted()
    camera = viewport.camera_from_view(
        view, window, cam.data.type != "ORTHO", w, h, scene.unit_settings.scale_length
    )
    f12_text = render_engine.scene_description_json(scene, depsgraph, native)
    vp_text = plate.scene_json(
        camera=camera, resolution=(w, h, 100), **render_engine.scene_world(scene, depsgraph, native)
    )
    f12 = native.SceneDescription.from_json_string(f12_text)
    vp = native.SceneDescription.from_json_string(vp_text)
    worst = 0.0
    for sx, sy in [(0.5, 0.5), (0.0, 0.0), (1.0, 1.0), (0.2, 0.8), (0.9, 0.1)]:
        o1, d1, _ = f12.camera_ray(sx, sy)
        o2, d2, _ = vp.camera_ray(sx, sy)
        worst = max(worst, math.acos(min(1.0, float(np.dot(d1, d2)))))
        t.check(np.allclose(o1, o2, atol=1e-4), f"{name}: ray origins {o1} vs {o2}")
    t.check(worst < 1e-6, f"{name}: rays differ by {worst:g} rad")
    a = native.camera_plate(f12)["combined"]
    b = native.camera_plate(vp)["combined"]
    floor = 1e-3 * float(a.mean())
    rel = float((np.abs(a - b) / np.maximum(np.abs(a), floor)).max())
    t.check(np.isfinite(b).all(), f"{name}: non-finite viewport plate")
    t.check(rel < 1e-4, f"{name}: viewport plate differs from F12's by {rel:g} (relative)")
    print(f"{name}: rays within {worst:.2e} rad, plate within {rel:.2e} relative")
t.done("test_viewport_camera")
