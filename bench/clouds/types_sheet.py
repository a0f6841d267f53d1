# SPDX-License-Identifier: Apache-2.0
"""The contact sheet of the cloud types (docs/clouds_types.png): one row per type, each
preset at its defaults seen from the ground at noon (sun 60 degrees up, camera 15 degrees
up), from the ground at sunset (sun 3 degrees up, 45 degrees to the right) and from above
(10 km up, looking 30 degrees down, sun 45 degrees up), beside what the WMO International
Cloud Atlas says the type looks like (in our words). Through the scene camera's plate
(welkin.camera_plate, the WELKIN render engine's picture); each view has one exposure for
every type, set from the clear sky of that view (its median maps to 0.25 before
x / (1 + x) and sRGB's curve), so a grey type reads grey beside a white one.

    PYTHONPATH=build /usr/bin/python3 bench/clouds/types_sheet.py            # docs/clouds_types.png
    ... /tmp/cu.png --types cumulus --width 480                             # one type, to look at it
    ... /tmp/cu1.png --types cumulus --lighting '{"surface_cut": 1}'        # a march setting changed
(needs numpy, Pillow and matplotlib's DejaVu font: scripts/install_deps.sh installs Debian's
python3-numpy and python3-matplotlib, which brings python3-pil and fonts-dejavu-core.)
"""

import argparse
import json
import math
import pathlib
import sys
import textwrap
import time

import numpy as np
from matplotlib import font_manager
from PIL import Image, ImageDraw, ImageFont

import welkin

ROOT = pathlib.Path(__file__).resolve().parents[2]

# What the WMO International Cloud Atlas (2017 online edition, "Definitions of clouds" and
# the species and varieties) describes, paraphrased.
ATLAS = {
    "cumulus": "Separate, dense heaps with crisp outlines that build upwards as mounds, domes "
    "or towers. The sunlit upper parts bulge like a cauliflower and are brilliant white; the "
    "bases are almost level and comparatively dark. Humilis: flattened, little depth; "
    "mediocris: about as tall as wide, small bulges on top. Blue sky between them.",
    "stratocumulus": "A low grey or whitish sheet or patches, nearly always with darker parts, "
    "made of rounded masses, rolls or tiles, joined or not. Seen more than 30 degrees up, "
    "each regular element is wider than about 5 degrees (three fingers at arm's length).",
    "altocumulus": "A mid-level white or grey sheet or patches of small rounded masses, "
    "rolls or flakes, with their own shading, often in regular rows; each element seen "
    "more than 30 degrees up spans between 1 and 5 degrees (a mackerel sky).",
    "stratus": "A generally grey layer with a fairly uniform base; it may give drizzle. When "
    "the sun shows through, its outline is clearly seen. No rolls or cells: an even sheet, "
    "sometimes in ragged shreds.",
    "cirrus": "Detached high clouds of white, delicate filaments or narrow bands, hair-like "
    "(fibrous), silky or both. Uncinus: comma-shaped strands ending in a hook or tuft at the "
    "top; the trails below are fallstreaks of ice crystals drifting in the wind's shear.",
}

VIEWS = {
    # name: (camera height m, pitch deg, sun elevation deg, sun azimuth deg right of the view)
    "ground, noon": (20.0, 15.0, 60.0, 60.0),
    "ground, sunset": (20.0, 15.0, 3.0, 45.0),
    "above (10 km)": (10000.0, -30.0, 45.0, 60.0),
}


def camera(height_m, pitch_deg, fov_deg=70.0):
    # Blender's camera looks down its local -Z with +Y up: a rotation about X by
    # 90 + pitch degrees looks towards +Y, pitched up by `pitch`.
    a = math.radians(90.0 + pitch_deg)
    c, s = math.cos(a), math.sin(a)
    return {
        "matrix_world": [[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, height_m], [0, 0, 0, 1]],
        "type": "PERSP",
        "fov_deg": fov_deg,
        "sensor_width_mm": 36,
        "sensor_height_mm": 24,
    }


def sun(elevation_deg, azimuth_deg):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return [math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)]


def render(cloud_type, view, width, steps, lighting=None):
    height_m, pitch, elevation, azimuth = VIEWS[view]
    scene = {
        "version": 1,
        "atmosphere": "bruneton2017",
        "sun": {"direction": sun(elevation, azimuth)},
        "camera": camera(height_m, pitch),
        "resolution": {"x": width, "y": width * 9 // 16, "percentage": 100},
    }
    if cloud_type:
        scene["clouds"] = {
            "layers": [{"cloud_type": cloud_type}],
            "lighting": {"max_steps": steps, **(lighting or {})},
        }
    return np.asarray(welkin.camera_plate(json.dumps(scene))["combined"], np.float64)[..., :3]


def tone(rgb, scale):
    x = np.maximum(rgb * scale, 0.0)
    x = x / (1.0 + x)
    return np.clip(np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055), 0, 1)


def font(size):
    return ImageFont.truetype(font_manager.findfont("DejaVu Sans"), size)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", nargs="?", default=str(ROOT / "docs" / "clouds_types.png"))
    ap.add_argument("--width", type=int, default=400, help="of each view, pixels")
    ap.add_argument("--steps", type=int, default=96, help="the march's view steps")
    ap.add_argument("--types", nargs="*", default=list(welkin.CLOUD_TYPES))
    ap.add_argument("--views", nargs="*", default=list(VIEWS))
    ap.add_argument("--lighting", type=json.loads, default={}, help="more clouds.lighting settings (JSON)")
    args = ap.parse_args()
    w, h = args.width, args.width * 9 // 16
    text_w, head_h = 330, 22
    scales = {}
    for v in args.views:  # each view's exposure, from its clear sky
        clear = render(None, v, w, args.steps)
        scales[v] = 0.25 / np.median(clear[: h * 3 // 4].mean(axis=2))
    sheet = Image.new("RGB", (text_w + w * len(args.views), head_h + h * len(args.types)), (18, 18, 18))
    d = ImageDraw.Draw(sheet)
    small, body, title = font(13), font(12), font(17)
    for i, v in enumerate(args.views):
        d.text((text_w + i * w + 6, 3), v, fill=(235, 235, 235), font=small)
    for r, t in enumerate(args.types):
        y0 = head_h + r * h
        d.text((8, y0 + 6), t, fill=(255, 255, 255), font=title)
        lines = textwrap.wrap(ATLAS[t], 47)
        for k, line in enumerate(lines):
            d.text((8, y0 + 32 + 15 * k), line, fill=(200, 200, 200), font=body)
        for i, v in enumerate(args.views):
            t0 = time.perf_counter()
            rgb = render(t, v, w, args.steps, args.lighting)
            print(f"{t:13s} {v:15s} {time.perf_counter() - t0:6.1f} s", file=sys.stderr)
            tile = Image.fromarray((tone(rgb, scales[v]) * 255 + 0.5).astype(np.uint8))
            sheet.paste(tile, (text_w + i * w, y0))
    sheet.save(args.out, optimize=True)
    print(f"wrote {args.out} ({pathlib.Path(args.out).stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
