# SPDX-License-Identifier: Apache-2.0
"""Renders the README's night picture: Paris (48.8566 N, 2.3522 E), four moments from
welkin.sky_image_at (the sun and the moon at their positions, the moonlit sky and the
moon's disc, the stars and the night sky's glow), equirectangular upper hemisphere, +Y
(north) a quarter from the left, from top to bottom:
  2026-06-29 22:45 CEST  sun 6.5 degrees down, the full moon rising (civil twilight's end);
  2026-08-12 22:45 CEST  sun 13.7 degrees down, no moon (new): a starry twilight;
  2026-06-30 01:30 CEST  sun 17.8 degrees down, the full moon 13 degrees up: moonlight;
  2026-08-13 00:30 CEST  sun and moon 24 degrees down: a moonless night.
Each panel is tone mapped for display with its own exposure (the 99th percentile of the
sky's luminance, then x / (1 + x), then sRGB gamma); each prints its zenith and its
display scale, whose ratios are the panels' brightness ratios in physical units.

    PYTHONPATH=build /usr/bin/python3 bench/render_night_picture.py docs/night.png
"""

import sys

import matplotlib.pyplot as plt
import numpy as np
import welkin

width, height = 1024, 512
out = sys.argv[1] if len(sys.argv) > 1 else "night.png"
atm = welkin.Atmosphere.preset("bruneton2017")
panels = []
moments = (
    "2026-06-29T22:45:00+02:00",
    "2026-08-12T22:45:00+02:00",
    "2026-06-30T01:30:00+02:00",
    "2026-08-13T00:30:00+02:00",
)
for time in moments:
    rgb = welkin.sky_image_at(atm, time, 48.8566, 2.3522, width, method="lut")
    sky = rgb[: height // 2]
    scale = 4.0 / np.percentile(sky.sum(axis=2) / 3, 99)
    x = sky * scale
    x = x / (1.0 + x)
    panels.append(np.clip(np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055), 0, 1))
    print(f"{time}: zenith {rgb[0, width // 2]} W m^-2 sr^-1 (Rec.709), display scale {scale:.3g}")
plt.imsave(out, np.concatenate(panels, axis=0))
print(f"wrote {out}")
