# SPDX-License-Identifier: Apache-2.0
"""Time of a camera plate with one cloud layer of each type at its preset, side by side: the
scene camera 20 m above the ground looking 15 degrees up (70 degree lens), the add-on's
default lighting, `welkin.camera_plate` (the WELKIN render engine's picture). Prints the
wall time and the process's CPU time (all threads: on a shared machine the wall time is not
the work), and both as ratios to the target (10 s for a 1920 x 1080 plate).

    PYTHONPATH=build /usr/bin/python3 bench/clouds/plate_types.py --width 1920
    ... --width 480 --types cumulus cirrus
    ... --lighting '{"surface_cut": 1}'      # clouds.lighting settings over the defaults
"""

import argparse
import json
import math
import os
import time

import welkin


# A 1920 x 1080 plate with one layer in this many seconds on two cores (the ratio columns).
TARGET_S = 10.0


def scene(cloud_type, width, upsampling=None, seed=None, lighting=None):
    a = math.radians(90.0 + 15.0)
    c, s = math.cos(a), math.sin(a)
    cam = {
        "matrix_world": [[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 20.0], [0, 0, 0, 1]],
        "type": "PERSP",
        "fov_deg": 70.0,
        "sensor_width_mm": 36,
        "sensor_height_mm": 24,
    }
    return {
        "version": 1,
        "atmosphere": "bruneton2017",
        "sun": {"direction": [0.55, 0.35, 0.6]},
        "camera": cam,
        "resolution": {"x": width, "y": width * 9 // 16, "percentage": 100},
        "clouds": {
            "layers": [{"cloud_type": cloud_type}],
            **({"upsampling": upsampling} if upsampling else {}),
            "lighting": {**({"seed": seed} if seed else {}), **(lighting or {})},
        },
    }


def render(text, band_rows=0):
    if not band_rows:
        return welkin.camera_plate(text)
    import numpy as np

    renderer = welkin.CameraPlateRenderer(text)
    h = renderer.height
    parts = []
    for r1 in range(h, 0, -band_rows):  # from the bottom up, as the engine's bands
        parts.append(renderer.render(rows=(max(0, r1 - band_rows), r1)))
    parts.reverse()
    return {k: np.concatenate([p[k] for p in parts]) for k in ("combined", "clouds")}


def timed(text, band_rows=0):
    w0, c0 = time.perf_counter(), time.process_time()
    plate = render(text, band_rows)
    return plate, time.perf_counter() - w0, time.process_time() - c0


def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


def errors(fast, exact):
    """Mean and p99 of the relative luminance error of "combined" and of |delta alpha|, over
    the pixels with cloud in either plate."""
    import numpy as np

    a, b = fast["clouds"][..., 3], exact["clouds"][..., 3]
    cloudy = (a > 0.01) | (b > 0.01)
    la, lb = luminance(fast["combined"])[cloudy], luminance(exact["combined"])[cloudy]
    rel = np.abs(la - lb) / np.maximum(lb, 1e-12)
    da = np.abs(a - b)[cloudy]
    return rel.mean(), np.percentile(rel, 99), da.mean(), np.percentile(da, 99), cloudy.mean()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--width", type=int, default=1920)
    ap.add_argument("--types", nargs="*", default=list(welkin.CLOUD_TYPES))
    ap.add_argument("--every-ray", action="store_true", help="also every ray marched: times and error")
    ap.add_argument("--reference-seeds", type=int, choices=(1, 2), default=1)
    ap.add_argument("--bands", type=int, default=0, help="render in bands of this many rows, as the engine")
    ap.add_argument("--lighting", type=json.loads, default={}, help="more clouds.lighting settings (JSON)")
    args = ap.parse_args()
    threads = len(os.sched_getaffinity(0))
    head = (
        f"| type | plate {args.width}x{args.width * 9 // 16} | CPU time (all threads) "
        f"| wall / {TARGET_S:.0f} s | CPU / {threads} threads / {TARGET_S:.0f} s |"
    )
    if args.every_ray:
        head += (
            " every ray: wall | CPU | default / every ray (CPU) | cloudy share "
            "| combined rel. error mean, p99 | alpha error mean, p99 |"
        )
        if args.reference_seeds == 2:
            head += " seed 2 against seed 1: combined mean, p99 | alpha mean, p99 |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for t in args.types:
        plate, wall, cpu = timed(json.dumps(scene(t, args.width, lighting=args.lighting)), args.bands)
        row = (
            f"| {t} | {wall:.2f} s | {cpu:.2f} s | {wall / TARGET_S:.2f}x | {cpu / threads / TARGET_S:.2f}x |"
        )
        if args.every_ray:
            exact, wall1, cpu1 = timed(
                json.dumps(scene(t, args.width, {"stride": 1}, lighting=args.lighting))
            )
            if args.reference_seeds == 2:
                second = welkin.camera_plate(
                    json.dumps(scene(t, args.width, {"stride": 1}, seed=2, lighting=args.lighting))
                )
                noise = errors(second, exact)
                exact = {k: 0.5 * (exact[k] + second[k]) for k in ("combined", "clouds")}
            m, p99, am, ap99, share = errors(plate, exact)
            row += (
                f" {wall1:.2f} s | {cpu1:.2f} s | {cpu / cpu1:.3f} | {share:.2f} | {100 * m:.2f} %, {100 * p99:.1f} % "
                f"| {am:.4f}, {ap99:.3f} |"
            )
            if args.reference_seeds == 2:
                row += f" {100 * noise[0]:.2f} %, {100 * noise[1]:.1f} % | {noise[2]:.4f}, {noise[3]:.3f} |"
        print(row, flush=True)


if __name__ == "__main__":
    main()
