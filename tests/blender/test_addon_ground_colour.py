# SPDX-License-Identifier: Apache-2.0
"""The ground below the horizon in the add-on's world: the preset's spectral albedo, or the
colour the artist picks in the sky panel ("Ground Colour"), made a reflectance spectrum by
the core (welkin.rgb_to_reflectance, Jakob & Hanika 2019).

Checks, on the world image the add-on makes (camera on the ground, so the view straight down
sees the ground with no air in between):
  * the panel shows the toggle and the colour;
  * the preset's ground (clear_day: green vegetation) is green, not grey: relative to a
    white ground's pixels, green > red and green > blue;
  * a picked colour's chromaticity comes back: the ground pixels over those of a grey ground
    of the colour's mean albedo (the same light, so the light cancels; the grey keeps the
    light the ground sends up and the sky sends back nearly the same, see
    tests/python/test_ground_colour.py) have the colour's r : g : b to 0.02 in chromaticity
    (r / (r + g + b)); a picked grey 0.3 gives 0.2-0.3 of a white ground's light;
  * the sky above leans toward the ground's colour (the ground lights it from below: a white
    ground doubles the blue overhead), in each channel in the colour's direction from the
    grey of its mean and by less than the colour departs from it.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()

scene, sun = T.new_scene(40.0, 60.0, resolution="256")
settings = scene.world.welkin
settings.preset = "clear_day"
settings.auto_update = False
shown = T.draw_panel(scene)
for name in ("use_preset_albedo", "ground_color"):
    T.check(("prop", name) in shown, f"the panel does not show {name}: {shown}")


def ground_and_sky(color=None):
    """(mean RGB of the rows looking 60-90 degrees down, mean RGB of the rows 30-90 up)."""
    settings.use_preset_albedo = color is None
    if color is not None:
        settings.ground_color = color
    bpy.ops.welkin.update_sky()
    sky = T.world_pixels(settings.sky_image).astype(np.float64)
    h = sky.shape[0]
    down = sky[h - h // 6 :].reshape(-1, 3).mean(axis=0)
    up = sky[: h // 3].reshape(-1, 3).mean(axis=0)
    T.check(np.all(np.isfinite(sky)) and np.all(sky >= 0.0), "non-finite or negative world pixels")
    return down, up


def chroma(rgb):
    return np.asarray(rgb, dtype=np.float64) / float(np.sum(rgb))


white_down, _ = ground_and_sky((1.0, 1.0, 1.0))
T.check(np.all(white_down > 0.0), f"the white ground is black: {white_down}")

preset_down, _ = ground_and_sky(None)
ratio = preset_down / white_down
T.check(
    ratio[1] > ratio[0] and ratio[1] > ratio[2],
    f"clear_day's vegetation ground is not green below the horizon: ratios to white {ratio}",
)
print(f"preset ground over white ground: {np.round(ratio, 4)} (green vegetation)")

for color in ((0.40, 0.25, 0.10), (0.10, 0.30, 0.12), (0.15, 0.20, 0.45)):
    mean = sum(color) / 3.0
    grey_down, grey_up = ground_and_sky((mean, mean, mean))
    down, up = ground_and_sky(color)
    got = chroma(down / grey_down)
    want = chroma(color)
    T.check(
        np.max(np.abs(got - want)) < 0.02,
        f"ground colour {color}: chromaticity below the horizon {np.round(got, 4)}, asked {np.round(want, 4)}",
    )
    # The sky above: lit from below by the ground too, so it leans toward the ground's
    # colour, channel by channel in the colour's direction, but by less than the colour
    # departs from its grey (the ground's share of the sky's light is below 1).
    d_sky = up / grey_up - 1.0
    d_colour = np.asarray(color) / mean - 1.0
    T.check(
        np.all((np.abs(d_colour) < 0.1) | (np.sign(d_sky) == np.sign(d_colour)))
        and np.all(np.abs(d_sky) <= np.abs(d_colour) + 0.01),
        f"ground colour {color}: the sky above over the grey of its mean {np.round(d_sky, 4)}, "
        f"the colour over its mean {np.round(d_colour, 4)}",
    )
    print(f"ground colour {color}: chromaticity {np.round(got, 4)} vs {np.round(want, 4)}")

down, _ = ground_and_sky((0.3, 0.3, 0.3))
grey = down / white_down
T.check(np.all(grey > 0.2) and np.all(grey <= 0.3 + 1e-4), f"a grey ground 0.3: ratios to white {grey}")
T.done("test_addon_ground_colour")
