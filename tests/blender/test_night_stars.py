# SPDX-License-Identifier: Apache-2.0
"""The night sky in the world (Place and Time): La Palma, 19 March 2026 00:30 UTC, a
moonless night (new moon, sun 51 degrees down). After Update Sky the world's image is
welkin.sky_image_at's for that moment without the discs (the night sky's glow and the
Hipparcos stars at their places), within 1e-5 of its brightest pixel; the stars stand out
of the glow (the brightest pixel is over 5 times the upper hemisphere's median: at 256
pixels wide a pixel spans 1.4 degrees, and a first-magnitude star there is some ten times
the glow); with Stars off the world
is the glow alone, and what the stars added is welkin.star_image of welkin.stars_at.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
scene, sun = T.new_scene(40.0, 30.0, resolution="256")
world = scene.world
world.welkin.method = "lut"
settings = world.welkin_place_time
settings.enabled = True
settings.year, settings.month, settings.day = 2026, 3, 19
settings.hours = 0.5
settings.utc_offset_h = 0.0
settings.latitude_deg, settings.longitude_deg = 28.7606, -17.8816
settings.height_m = 2396.0
bpy.ops.welkin.update_sky()
T.check(world.welkin.active, f"no sky: {world.welkin.status}")

TIME = "2026-03-19T00:30:00+00:00"
positions = welkin.sun_and_moon(TIME, 28.7606, -17.8816, height_m=2396.0)
T.check(
    positions["sun"]["elevation_deg"] < -18.0 and positions["moon"]["elevation_deg"] < 0.0, "not a dark night"
)
atm = welkin.Atmosphere.preset(world.welkin.preset)
expected = welkin.sky_image_at(atm, TIME, 28.7606, -17.8816, 256, "lut", height_m=2396.0, discs=False)
sky = T.world_pixels(world.welkin.sky_image)
peak = float(expected.max())
error = float(np.abs(sky - expected).max())
print(
    f"world vs sky_image_at: max difference {error:.3g} of peak {peak:.3g}; median {float(np.median(sky)):.3g}"
)
T.check(error <= 1e-5 * peak, "the world's night sky is not the module's")
upper = float(np.median(sky[: sky.shape[0] // 2]))
print(f"brightest pixel / the sky's median: {peak / upper:.3g}")
T.check(peak > 5.0 * upper, "no stars stand out of the glow")

settings.stars = False
bpy.ops.welkin.update_sky()
glow = T.world_pixels(world.welkin.sky_image)
stars = welkin.star_image(atm, welkin.stars_at(TIME, 28.7606, -17.8816, height_m=2396.0), 256)
error = float(np.abs((sky - glow) - stars).max())
print(f"stars off: the stars' part vs star_image: max difference {error:.3g}")
T.check(error <= 1e-5 * peak, "the stars' part is not welkin.star_image")
T.check(float((sky - glow).max()) > 0.5 * peak, "Stars off did not take the brightest stars away")
T.done("test_night_stars")
