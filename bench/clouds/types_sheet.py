# SPDX-License-Identifier: Apache-2.0
"""The contact sheet of the cloud types (docs/clouds_types.png): each preset seen from the
ground (looking 15 degrees up) and from above (12 km up, looking 30 degrees down), through
the scene camera's plate (welkin.camera_plate, the WELKIN render engine's picture), tone
mapped (exposure per type, x / (1 + x), sRGB gamma); the march at 48 view steps to keep it quick.

    PYTHONPATH=build /usr/bin/python3 bench/clouds/types_sheet.py docs/clouds_types.png
    ... --views ground --width 480 --types cumulus      # one type, to look at it
(needs numpy and Pillow: scripts/install_deps.sh installs Debian's python3-numpy, and
python3-matplotlib brings python3-pil.)
"""

import argparse
import json
import math
import pathlib
import sys

import numpy as np
from PIL import Image, ImageDraw

import welkin

ROOT = pathlib.Path(__file__).resolve().parents[2]


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


def render(cloud_type, view, width, coverage=None, detail=None):
    height = width * 9 // 16
    layer = {"cloud_type": cloud_type}
    if coverage is not None:
        layer["coverage"] = coverage
    if detail is not None:
        layer["detail_strength"] = detail
    cam = camera(20.0, 15.0) if view == "ground" else camera(12000.0, -30.0)
    scene = {
        "version": 1,
        "atmosphere": "bruneton2017",
        "sun": {"direction": [0.55, 0.35, 0.6]},
        "camera": cam,
        "resolution": {"x": width, "y": height, "percentage": 100},
        "clouds": {"layers": [layer], "lighting": {"max_steps": 48, "light_steps": 6}},
    }
    plate = welkin.camera_plate(json.dumps(scene))
    return plate["combined"]


def tone(rgb, scale):
    x = rgb * scale
    x = x / (1.0 + x)
    return np.clip(np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.abs(x) ** (1 / 2.4) - 0.055), 0, 1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", nargs="?", default=str(ROOT / "docs" / "clouds_types.png"))
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--types", nargs="*", default=list(welkin.CLOUD_TYPES))
    ap.add_argument("--views", nargs="*", default=["ground", "above"])
    ap.add_argument("--coverage", type=float, default=None)
    ap.add_argument("--detail", type=float, default=None)
    ap.add_argument("--cache", default=None, help="a folder: each type's row is kept there and reused")
    args = ap.parse_args()
    rows = []
    for t in args.types:
        cached = pathlib.Path(args.cache) / f"{t}.png" if args.cache else None
        if cached and cached.exists():
            rows.append(np.asarray(Image.open(cached)))
            continue
        tiles = []
        scale = None
        for v in args.views:
            rgb = render(t, v, args.width, args.coverage, args.detail)
            # One exposure per type, from the ground view: its 90th percentile (the bright
            # clouds and sky, the ground left out) maps to 1.2 before x / (1 + x).
            if scale is None:
                scale = 1.2 / np.percentile(rgb.mean(axis=2)[: rgb.shape[0] * 3 // 4], 90)
            tiles.append(tone(rgb, scale))
            print(f"{t} {v}: mean {rgb.mean():.4f}", file=sys.stderr)
        row = np.concatenate(tiles, axis=1)
        img = Image.fromarray((row * 255 + 0.5).astype(np.uint8))
        d = ImageDraw.Draw(img)
        d.rectangle([0, 0, 8 + 7 * len(t), 14], fill=(0, 0, 0))
        d.text((4, 2), t, fill=(255, 255, 255))
        if cached:
            cached.parent.mkdir(parents=True, exist_ok=True)
            img.save(cached)
        rows.append(np.asarray(img))
    sheet = Image.fromarray(np.concatenate(rows, axis=0))
    sheet.save(args.out, optimize=True)
    print(f"wrote {args.out} ({pathlib.Path(args.out).stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
