# SPDX-License-Identifier: Apache-2.0
"""Shade Sun Lamp: the sun lamp follows the clouds' transmittance towards the sun at the
scene origin; under a total overcast it dims and the props' shadows soften.

One cloud layer over a sun 40 degrees up; Update Sky each time:

  * clear (the layer off): the lamp's strength E0 (the clear sun's, as before);
  * a thin layer (T towards the sun between 0.05 and 0.95, the core's
    welkin.cloud_transmittance for the scene's clouds at the origin, whose march is checked
    against Beer-Lambert's closed form in tests/cpp/test_cloud_shadow.cpp): strength
    E0 x T within 1e-5 relative, colour the clear sun's (grey extinction) within 1e-6;
  * a total overcast (coverage 1, dense): strength below 1 % of E0;
  * Shade Sun Lamp off under the overcast: E0 again (the clear sun's, exactly as stored);
  * Cycles (orthographic top view of a ground plane and a 2 m cube, 16 samples, the
    cloudy world lighting too): the cube's shadow, the ground pixels darker than half
    their brightness without the cube under the clear sky, is at least twice as light
    relative to the unshadowed ground under the overcast (soft, sky-lit) as under the clear
    sky (hard, sun-lit): measured ratios in the log.

Run: PYTHONPATH=$PWD/build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_lamp_shadow.py
"""

import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

addon, native = t.install_addon()
from welkin.blender import compat  # noqa: E402
from welkin.blender.sky import scene_sun, update  # noqa: E402

check = t.check
scene, sun = t.new_scene(sun_elevation_deg=40.0, sun_azimuth_deg=0.0, camera_z=20.0)
world = scene.world
c = ct.quick_cloudy_world(world)
check(c.shadows, "Shade Sun Lamp must be on by default")
layer = ct.add_layer(
    world,
    bottom_altitude_m=1000.0,
    top_altitude_m=1800.0,
    coverage=1.0,
    weather_variation=0.0,
    density_per_m=0.0004,
)


def lamp_after_update():
    bpy.ops.welkin.update_sky()
    return sun.data.energy, tuple(sun.data.color)


def core_transmittance():
    request, _lamp, _w = scene_sun.request_for(scene, world.welkin, None)
    text = update.shadow_scene_json(scene, world.welkin, request, update.clouds_of(scene), native)
    return float(native.cloud_transmittance(text, np.zeros((1, 3)))[0])


layer.enabled = False
e0, colour0 = lamp_after_update()
layer.enabled = True
T = core_transmittance()
e1, colour1 = lamp_after_update()
print(
    f"thin layer: T towards the sun {T:.4f}; lamp {e1:.4f} W/m2 vs clear {e0:.4f} "
    f"({e1 / e0:.4f}); status: {world.welkin.status}"
)
check(0.05 < T < 0.95, f"the thin layer's T {T} is not in (0.05, 0.95)")
check(abs(e1 / (e0 * T) - 1.0) < 1e-5, f"lamp {e1} != clear {e0} x T {T}")
check(max(abs(a - b) for a, b in zip(colour0, colour1)) < 1e-6, f"colour {colour1} vs {colour0}")

layer.density_per_m = 0.05
T_overcast = core_transmittance()
e2, _ = lamp_after_update()
print(f"overcast: T {T_overcast:.2e}; lamp {e2:.3g} W/m2 ({e2 / e0:.2e} of clear)")
check(e2 < 0.01 * e0, f"under a total overcast the lamp keeps {e2 / e0:.3f} of its strength")

c.shadows = False
e3, _ = lamp_after_update()
check(e3 == e0, f"Shade Sun Lamp off: {e3} vs the clear {e0}")
c.shadows = True

# --- The props' shadows in Cycles: hard under the clear sky, soft under the overcast.
bpy.ops.mesh.primitive_plane_add(size=40.0, location=(0.0, 0.0, 0.0))
bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0.0, 0.0, 1.0))
cube = bpy.context.active_object
cam = scene.camera
cam.location = (0.0, 0.0, 20.0)
cam.rotation_euler = (0.0, 0.0, 0.0)
cam.data.type = "ORTHO"
cam.data.ortho_scale = 12.0
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False
scene.cycles.seed = 1
scene.render.resolution_x = scene.render.resolution_y = 48
scene.render.resolution_percentage = 100
compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
scene.render.image_settings.color_depth = "32"
scene.view_settings.view_transform = "Standard"


def shot(name):
    t.render_still(scene, t.TMP / name)
    return t.read_rgb_exr(native, t.TMP / name).mean(axis=-1)


def ratios():
    bpy.ops.welkin.update_sky()
    cube.hide_render = False
    with_cube = shot("with.exr")
    cube.hide_render = True
    without = shot("without.exr")
    cube.hide_render = False
    return with_cube / np.maximum(without, 1e-9)


layer.enabled = False
clear = ratios()
# The ground in the cube's shadow under the clear sky: darker than half, off the cube's
# footprint (the cube's top, 2 m wide, seen from above: 8 pixels at 4 pixels per metre).
ys, xs = np.mgrid[0:48, 0:48]
footprint = (np.abs(xs - 23.5) < 5) & (np.abs(ys - 23.5) < 5)
shadow = (clear < 0.5) & ~footprint
check(shadow.sum() > 10, f"the clear sky's shadow covers {shadow.sum()} pixels")
layer.enabled = True
overcast = ratios()
hard, soft = float(clear[shadow].mean()), float(overcast[shadow].mean())
print(
    f"the shadow's brightness relative to the open ground: clear {hard:.3f}, "
    f"overcast {soft:.3f} ({shadow.sum()} pixels); lamp {sun.data.energy:.3g} W/m2"
)
check(
    1.0 - soft < 0.5 * (1.0 - hard),
    f"the overcast shadow is not soft: {soft:.3f} of the open ground vs {hard:.3f} clear",
)
t.done("test_cloud_lamp_shadow")
