# SPDX-License-Identifier: Apache-2.0
"""Time of a camera plate with one cloud layer of each type at its preset, side by side: the
scene camera 20 m above the ground looking 15 degrees up (70 degree lens), the add-on's
default lighting, `welkin.camera_plate` (the WELKIN render engine's picture). Prints the
wall time and the process's CPU time (all threads: on a shared machine the wall time is not
the work), and both as ratios to the target (10 s for a 1920 x 1080 plate).

    PYTHONPATH=build /usr/bin/python3 bench/clouds/plate_types.py --width 1920
    ... --width 480 --types cumulus cirrus
"""

import argparse
import json
import math
import os
import time

import welkin


# A 1920 x 1080 plate with one layer in this many seconds on two cores (the ratio columns).
TARGET_S = 10.0


def scene(cloud_type, width):
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
        "clouds": {"layers": [{"cloud_type": cloud_type}]},
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--width", type=int, default=1920)
    ap.add_argument("--types", nargs="*", default=list(welkin.CLOUD_TYPES))
    args = ap.parse_args()
    print(
        f"| type | plate {args.width}x{args.width * 9 // 16} | CPU time (all threads) "
        f"| wall / {TARGET_S:.0f} s | CPU / {len(os.sched_getaffinity(0))} threads / {TARGET_S:.0f} s |\n|---|---|---|---|---|"
    )
    for t in args.types:
        text = json.dumps(scene(t, args.width))
        w0, c0 = time.perf_counter(), time.process_time()
        welkin.camera_plate(text)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        print(
            f"| {t} | {wall:.2f} s | {cpu:.2f} s | {wall / TARGET_S:.2f}x | {cpu / len(os.sched_getaffinity(0)) / TARGET_S:.2f}x |",
            flush=True,
        )


if __name__ == "__main__":
    main()
