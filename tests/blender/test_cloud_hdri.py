# SPDX-License-Identifier: Apache-2.0
"""Export HDRI writes the sky the world shows, its clouds included.

A world with a procedural cloud layer (Update Sky, 256 x 128, the camera 2 m up); then
welkin.export_hdri at the world's width:

  * without the sun's disc, the EXR equals the world's sky image (the same core call on
    the same scene): every pixel within 1e-5 relative (of max(value, 1e-6 x the mean));
  * with the disc, it equals the world's sky image plus its disc image (the disc the
    world shows to the camera, dimmed by the clouds) away from the sun's pixels within
    1e-5 as above, and in total (sum over the sphere weighted by each row's solid angle)
    within 1e-3;
  * it is not the clear sky: where the clouds' transmittance is below 0.9 (the core's,
    for this scene), over 90 % of the pixels differ from the clear HDRI (the layer
    switched off, exported again) by more than 1 %; where it is 1, they agree within 1e-5.

Run: PYTHONPATH=$PWD/build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_hdri.py
"""

import math
import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

addon, native = t.install_addon()
from welkin.blender.sky import scene_sun, update  # noqa: E402

check = t.check
scene, sun = t.new_scene(sun_elevation_deg=25.0, sun_azimuth_deg=30.0, camera_z=2.0)
world = scene.world
c = ct.quick_cloudy_world(world)
layer = ct.add_layer(
    world,
    bottom_altitude_m=1000.0,
    top_altitude_m=1800.0,
    coverage=0.6,
    density_per_m=0.02,
    base_scale_m=3000.0,
    weather_scale_m=12000.0,
)
bpy.ops.welkin.update_sky()
check("with clouds" in world.welkin.status, world.welkin.status)
sky = t.world_pixels(world.welkin.sky_image).copy()
# The world draws the disc with nodes; the HDRI holds it as pixels: the core's disc image
# for this sun, dimmed by the clouds' transmittance of each pixel (as the core composites).
from welkin import sky_request  # noqa: E402

request, _lamp, _w = scene_sun.request_for(scene, world.welkin, None)
text = update.cloudy_scene_json(scene, world.welkin, request, update.clouds_of(scene), native)
_img, T = native.scene_sky_image(
    native.SceneDescription.from_json_string(text), sky.shape[1], sun_disc=False, return_transmittance=True
)
disc = (
    native.sun_disc_image(
        sky_request.build_atmosphere(request, native),
        request.altitude_m,
        request.sun_direction,
        sky.shape[1],
        "rgb",
        exposure=request.exposure,
    )
    * T[..., None]
)


def export(name, **kwargs):
    path = t.TMP / name
    bpy.ops.welkin.export_hdri(filepath=str(path), **kwargs)
    return t.read_rgb_exr(native, path)


def relative(a, ref):
    return np.abs(a - ref) / np.maximum(np.abs(ref), 1e-6 * float(np.abs(ref).mean()))


no_disc = export("cloudy_nodisc.exr", sun_disc=False)
check(no_disc.shape == sky.shape, f"HDRI shape {no_disc.shape}, world {sky.shape}")
err = relative(no_disc, sky).max()
print(f"HDRI without disc vs the world's sky image: max relative difference {err:.2e}")
check(err < 1e-5, f"the HDRI without disc differs from the world's sky by {err:.3g}")

with_disc = export("cloudy_disc.exr", sun_disc=True)
world_total = sky + disc
sun_pixels = (disc.max(axis=-1) > 0.0) | (np.abs(with_disc - no_disc).max(axis=-1) > 0.0)
check(sun_pixels.sum() < 0.01 * sun_pixels.size, f"{sun_pixels.sum()} pixels hold the disc")
err = relative(with_disc, world_total)[~sun_pixels].max()
check(err < 1e-5, f"the HDRI with disc differs from the world away from the sun by {err:.3g}")
h = sky.shape[0]
weight = np.cos((np.arange(h) + 0.5) / h * math.pi - math.pi / 2.0)[:, None, None]
total_hdri, total_world = float((with_disc * weight).sum()), float((world_total * weight).sum())
rel = abs(total_hdri / total_world - 1.0)
print(f"HDRI with disc vs the world's sky + disc: total {rel:.2e} relative, away from the sun {err:.2e}")
check(rel < 1e-3, f"the HDRI's total differs from the world's (sky + disc) by {rel:.3g}")

# The clouds are in it: against the clear sky, where the core sees clouds.
layer.enabled = False
clear = export("clear_nodisc.exr", sun_disc=False)
cloud, free = T < 0.9, T >= 1.0 - 1e-7
check(
    cloud.sum() > 0.05 * T.size and free.sum() > 0.1 * T.size,
    f"the test wants cloudy and clear pixels: {cloud.mean():.2f} cloudy, {free.mean():.2f} free",
)
changed = float((relative(no_disc, clear).max(axis=-1)[cloud] > 0.01).mean())
same = float(relative(no_disc, clear).max(axis=-1)[free].max())
print(
    f"cloudy HDRI vs clear HDRI: {cloud.mean():.1%} of the sphere clouded (T < 0.9), "
    f"{changed:.1%} of it changed by over 1 %; cloud-free pixels agree to {same:.1e}"
)
check(changed > 0.9, f"only {changed:.1%} of the clouded pixels differ from the clear sky")
check(same < 1e-5, f"cloud-free pixels differ from the clear sky by {same:.3g}")
t.done("test_cloud_hdri")
