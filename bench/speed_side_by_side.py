# SPDX-License-Identifier: Apache-2.0
"""Two builds of the Python module side by side: the LUT rebuild and the 2048 x 1024 `lut`
sky image, for each build's default preset (a build without `clear_day` uses bruneton2017, its
default) and for bruneton2017 in both, run alternately so that both see the same load.

    PYTHONPATH=build /usr/bin/python3 bench/speed_side_by_side.py --baseline OTHER/build \
        [--repeats 15]

Each measurement runs in a fresh interpreter with one build's module on its path (the
other build: --baseline, a build folder holding welkin*.so). Per repeat: the LUT rebuild
is welkin.sky_radiance of one view with an atmosphere not seen before (its ozone scaled by
1 + 1e-9 k: every LUT is rebuilt, the sky-view LUT included); the image is welkin.sky_image
at 2048 x 1024, lut, with the sun moved (the atmosphere's LUTs cached, as when a lamp
turns), disc and ground on. Times are the process's CPU time (all threads), which a
shared, loaded machine disturbs less than the wall clock. Prints the medians and the ratio
(this build / baseline).
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]

CHILD = r"""
import json, math, sys, time
import numpy as np
import welkin
preset, k = sys.argv[1], int(sys.argv[2])
names = welkin.Atmosphere.preset_names()
atm = welkin.Atmosphere.preset(preset if preset in names else "bruneton2017")
sun = lambda e: (math.cos(math.radians(e)), 0.0, math.sin(math.radians(e)))
view = np.array([[0.0, 0.6, 0.8]])
welkin.sky_image(atm, 0.0, sun(30.0), 256)  # warm up: threads, caches
out = {"rebuild": [], "image": []}
for r in range(3):
    a = atm.copy()
    a.absorption_extinction = a.absorption_extinction * (1.0 + 1e-9 * (k * 3 + r + 1))
    t = time.process_time(); welkin.sky_radiance(a, 0.0, sun(30.0), view, "lut", "rgb")
    out["rebuild"].append(time.process_time() - t)
    t = time.process_time(); welkin.sky_image(atm, 0.0, sun(20.0 + r + 0.1 * k), 2048, "lut")
    out["image"].append(time.process_time() - t)
print(json.dumps(out))
"""


def measure(build, preset, k):
    env = dict(os.environ, PYTHONPATH=str(build))
    r = subprocess.run(
        [sys.executable, "-c", CHILD, preset, str(k)], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(r.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, help="build folder of the other module")
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    mine = ROOT / "build"
    print("| preset | what | this build (CPU) | baseline (CPU) | ratio |\n|---|---|---|---|---|")
    for preset in ("clear_day", "bruneton2017"):
        res = {"this": {"rebuild": [], "image": []}, "base": {"rebuild": [], "image": []}}
        for k in range(args.repeats):
            for side, build in (("this", mine), ("base", pathlib.Path(args.baseline))):
                m = measure(build, preset, k)
                for key in m:
                    res[side][key] += m[key]
        for key, label in (("rebuild", "LUT rebuild"), ("image", "2048x1024 lut image")):
            a, b = statistics.median(res["this"][key]), statistics.median(res["base"][key])
            print(f"| {preset} | {label} | {1e3 * a:.1f} ms | {1e3 * b:.1f} ms | {a / b:.3f} |")


if __name__ == "__main__":
    main()
