# SPDX-License-Identifier: Apache-2.0
"""Time of a camera plate with one cloud layer of each type at its preset, side by side: the
scene camera 20 m above the ground looking 15 degrees up (70 degree lens), the add-on's
default lighting, `welkin.camera_plate` (the WELKIN render engine's picture). Prints the
wall time and the process's CPU time (all threads: on a shared machine the wall time is not
the work).

    PYTHONPATH=build /usr/bin/python3 bench/clouds/plate_types.py --width 1920
    ... --width 480 --types cumulus cirrus
"""

import argparse
import json
import math
import time

import welkin


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
    print(f"| type | plate {args.width}x{args.width * 9 // 16} | CPU time (all threads) |\n|---|---|---|")
    for t in args.types:
        text = json.dumps(scene(t, args.width))
        w0, c0 = time.perf_counter(), time.process_time()
        welkin.camera_plate(text)
        print(f"| {t} | {time.perf_counter() - w0:.2f} s | {time.process_time() - c0:.2f} s |", flush=True)


if __name__ == "__main__":
    main()
