# SPDX-License-Identifier: Apache-2.0
"""Time of a cloudy sky made again after the sun turns, each type at its preset, with the
clouds' view samples kept from the sky before (welkin.scene_sky_image's default,
clouds/lighting.hpp CloudViewCache) and marched afresh (keep_cloud_samples=False): what the
add-on's live update does after a lamp rotation, a preview and then the sky.

    PYTHONPATH=build /usr/bin/python3 bench/clouds/kept_samples.py
    ... --widths 256 1024 --turns 5 --types altocumulus cirrus

Per type and width: the sky once, then --turns times with the sun 8 degrees further round
(and 6 degrees lower each time); the median seconds of those, kept and afresh. With two
widths the preview's and the sky's kept samples are each their own (two slots); every
kept image is checked against the fresh one, bit for bit.
"""

import argparse
import json
import math
import statistics
import sys
import time

import numpy as np

import welkin


def scene(cloud_type, elevation_deg, azimuth_deg):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return json.dumps(
        {
            "version": 1,
            "sun": {"direction": [math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)]},
            "clouds": {"layers": [{"cloud_type": cloud_type}]},
        }
    )


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--widths", type=int, nargs="+", default=[256, 1024])
    parser.add_argument("--turns", type=int, default=5)
    parser.add_argument("--types", nargs="+", default=list(welkin.CLOUD_TYPES), choices=welkin.CLOUD_TYPES)
    args = parser.parse_args(argv)
    if args.turns < 1 or min(args.widths) < 16:
        parser.error("--turns must be at least 1 and every width at least 16")

    print("| type | " + " | ".join(f"{w}: kept / afresh" for w in args.widths) + " |")
    print("|---|" + "---|" * len(args.widths))
    for t in args.types:
        kept = {w: [] for w in args.widths}
        fresh = {w: [] for w in args.widths}
        for turn in range(args.turns + 1):
            text = scene(t, 40.0 - 6.0 * turn, 60.0 + 8.0 * turn)
            for w in args.widths:
                t0 = time.perf_counter()
                image = welkin.scene_sky_image(text, w)
                t1 = time.perf_counter()
                again = welkin.scene_sky_image(text, w, keep_cloud_samples=False)
                t2 = time.perf_counter()
                if not np.array_equal(image, again):
                    raise SystemExit(f"kept_samples: {t} at {w}: the kept samples' sky is not the march's")
                if turn > 0:  # the first: nothing kept yet
                    kept[w].append(t1 - t0)
                    fresh[w].append(t2 - t1)
        med = statistics.median
        cells = [f"{med(kept[w]):.2f} s / {med(fresh[w]):.2f} s" for w in args.widths]
        print(f"| {t} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
