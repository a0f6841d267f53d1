# SPDX-License-Identifier: Apache-2.0
"""The night sky under the world's clouds (Place and Time with a cloud layer): La Palma, 19
March 2026 00:30 UTC, a moonless night (sun 59.5 degrees down), under a layer of thick
cumulus (1.5 to 2.5 km up, half the sky covered, 0.05 per metre: optical depths in the
tens). After Update Sky the world's stars (the world with Stars on minus the world with
Stars off) are, pixel by pixel, welkin.star_image of welkin.stars_at times the clouds'
transmittance there (welkin.scene_sky_image's, for the world's own cloudy scene): in the
clear gaps (T > 0.99) as bright as in a clear sky, within 1e-3 per pixel (of the star and
1e-6 of its pixel: float32 rounding) and 1e-4 in total; behind the thick clouds
(T < 0.01) under 1 % of it. Both kinds of pixel are plentiful (over 30 star pixels each).

Run: bash scripts/test_blender.sh -v 3.4,5.3 tests/blender/test_night_clouds.py
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402
import cloud_testing as ct  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender.sky import scene_sun, update  # noqa: E402

WIDTH = 256
TIME = "2026-03-19T00:30:00+00:00"
LAT, LON, HEIGHT = 28.7606, -17.8816, 2396.0
scene, sun = T.new_scene(40.0, 30.0, resolution=str(WIDTH))
world = scene.world
ct.quick_cloudy_world(world)
ct.add_layer(
    world,
    bottom_altitude_m=1500.0,
    top_altitude_m=2500.0,
    coverage=0.5,
    density_per_m=0.05,
    base_scale_m=4000.0,
    weather_scale_m=12000.0,
)
settings = world.welkin_place_time
settings.enabled = True
settings.year, settings.month, settings.day = 2026, 3, 19
settings.hours = 0.5
settings.utc_offset_h = 0.0
settings.latitude_deg, settings.longitude_deg = LAT, LON
settings.height_m = HEIGHT
bpy.ops.welkin.update_sky()
T.check(world.welkin.active, f"no sky: {world.welkin.status}")
T.check("with clouds" in world.welkin.status, world.welkin.status)
sky = T.world_pixels(world.welkin.sky_image).astype(np.float64)
T.check(np.isfinite(sky).all() and (sky >= 0.0).all(), "the cloudy night world has NaN or negative values")

settings.stars = False
bpy.ops.welkin.update_sky()
glow = T.world_pixels(world.welkin.sky_image).astype(np.float64)
starlight = (sky - glow).sum(axis=2)

atm = welkin.Atmosphere.preset(world.welkin.preset)
clear = welkin.star_image(atm, welkin.stars_at(TIME, LAT, LON, height_m=HEIGHT), WIDTH).astype(np.float64)
clear = clear.sum(axis=2)
request, _lamp, _warnings = scene_sun.request_for(scene, world.welkin, None)
text = update.cloudy_scene_json(scene, world.welkin, request, update.clouds_of(scene), welkin)
_img, t = welkin.scene_sky_image(
    welkin.SceneDescription.from_json_string(text), WIDTH, sun_disc=False, return_transmittance=True
)
gaps = (t > 0.99) & (clear > 0.0)
overcast = (t < 0.01) & (clear > 0.0)
print(f"star pixels in the gaps: {int(gaps.sum())}, behind thick cloud: {int(overcast.sum())}")
T.check(gaps.sum() > 30 and overcast.sum() > 30, "the layer leaves too few star pixels of either kind")
# A faint star is a small part of its pixel, so float32 rounding of the world's pixels
# (its 2^-24 of the pixel, twice) is a larger part of the star: allow 1e-6 of the pixel.
rounding = 1e-6 * sky.sum(axis=2)
excess = np.maximum(np.abs(starlight[gaps] - clear[gaps] * t[gaps]) - rounding[gaps], 0.0)
gap_error = float(np.max(excess / clear[gaps]))
print(f"stars in the gaps vs a clear sky's: max relative difference {gap_error:.3g} (beyond rounding)")
T.check(gap_error <= 1e-3, "the stars in the clear gaps are not the clear sky's")
total = float(starlight[gaps].sum() / (clear[gaps] * t[gaps]).sum())
print(f"the gaps' starlight / the clear sky's: {total:.6f}")
T.check(abs(total - 1.0) <= 1e-4, "the starlight in the clear gaps is not the clear sky's")
floor = 1e-6 * float(clear.max())
behind = float(np.max(starlight[overcast] / (clear[overcast] + floor)))
print(f"stars behind thick cloud: at most {behind:.3g} of their clear-sky light")
T.check(behind <= 0.01, "stars shine through thick clouds")
T.check(float(starlight[overcast].sum()) < 0.01 * float(clear[overcast].sum()), "stars behind the clouds")
T.done("test_night_clouds")
