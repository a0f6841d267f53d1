# SPDX-License-Identifier: Apache-2.0
"""The camera plate whole against in tiles, side by side in one run: camera_plate(scene)
for the whole frame, CameraPlateRenderer(scene) + render(rows=...) for each band of
--rows rows (what the render engine does), and camera_plate(scene, rows=...) per band
(every band redoing the frame-wide part, as the engine did before). Checks that the
prepared bands equal the whole frame exactly. Median of --repeats.

    PYTHONPATH=build /usr/bin/python3 bench/plate_tiles.py [--width 1920 --height 1080 --rows 64]
"""

import argparse
import json
import statistics
import time

import numpy as np

import welkin


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--width", type=int, default=1920)
    ap.add_argument("--height", type=int, default=1080)
    ap.add_argument("--rows", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--method", default="auto")
    args = ap.parse_args()
    scene = welkin.SceneDescription.from_json_string(
        json.dumps(
            {
                "version": 1,
                "atmosphere": "bruneton2017",
                "method": args.method,
                "sun": {"elevation_deg": 12, "azimuth_deg": 40},
                # 30 m up, looking along +X at the horizon: half sky, half aerial ground.
                "camera": {
                    "matrix_world": [[0, 0, -1, 0], [-1, 0, 0, 0], [0, 1, 0, 30], [0, 0, 0, 1]],
                    "type": "PERSP",
                    "lens_mm": 30,
                },
                "resolution": {"x": args.width, "y": args.height, "percentage": 100},
            }
        )
    )
    bands = [(r, min(r + args.rows, args.height)) for r in range(0, args.height, args.rows)]

    def whole():
        return welkin.camera_plate(scene)

    def prepared():
        renderer = welkin.CameraPlateRenderer(scene)
        return [renderer.render(rows=b) for b in bands]

    def per_call():
        return [welkin.camera_plate(scene, rows=b) for b in bands]

    whole()  # atmosphere LUT cache warm, as in a Blender session
    times = {"whole": [], "prepared bands": [], "per-call bands": []}
    for _ in range(args.repeats):
        for name, fn in (("whole", whole), ("prepared bands", prepared), ("per-call bands", per_call)):
            t = time.perf_counter()
            out = fn()
            times[name].append(time.perf_counter() - t)
            if name == "whole":
                full = out
            elif name == "prepared bands":
                for key in ("combined", "sky", "inscatter", "transmittance", "depth"):
                    assert np.array_equal(np.concatenate([b[key] for b in out]), full[key]), key
    base = statistics.median(times["whole"])
    print(
        f"{args.width} x {args.height}, {len(bands)} bands of {args.rows} rows, method "
        f"{full['method']}, median of {args.repeats}:"
    )
    for name, ts in times.items():
        m = statistics.median(ts)
        print(f"  {name:15s} {m:7.3f} s  ({m / base:.2f} x whole)")


if __name__ == "__main__":
    main()
