# SPDX-License-Identifier: Apache-2.0
"""Renders the README's picture: an equirectangular sky from the `welkin` module, tone
mapped for display (exposure, then x / (1 + x), then sRGB gamma), as PNG.

    PYTHONPATH=build /usr/bin/python3 bench/render_picture.py docs/sky.png
"""

import sys

import matplotlib.pyplot as plt
import numpy as np
import welkin

width, height = 1024, 512
out = sys.argv[1] if len(sys.argv) > 1 else "sky.png"
atm = welkin.Atmosphere.preset("bruneton2017")
dirs = welkin.equirect_pixel_directions(width, height).reshape(-1, 3)
panels = []
for elevation_deg in (30.0, 4.0):
    e = np.radians(elevation_deg)
    sun = (np.cos(e), 0.0, np.sin(e))
    rgb = welkin.sky_radiance(
        atm, altitude_m=0.0, sun_direction=sun, view_directions=dirs, method="lut", output="rgb"
    ).reshape(height, width, 3)
    x = rgb * (4.0 / np.percentile(rgb[: height // 2].sum(axis=2) / 3, 99))
    x = x / (1.0 + x)
    panels.append(np.clip(np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055), 0, 1))
# Upper hemisphere only: below the horizon the sky method gives path radiance, no ground.
plt.imsave(out, np.concatenate([p[: height // 2] for p in panels], axis=0))
print(f"wrote {out}")
