# SPDX-License-Identifier: Apache-2.0
"""Every cloud type's equirect sky, saved, and compared with another build's: what a change
to the march does to the picture.

Each type at its preset, one layer, the sun as in bench/clouds/bench_clouds.cpp (direction
(0.6, 0.2, 0.5)), `welkin.scene_sky_image` (what `welkin sky --scene` writes) with the clouds'
transmittance. `--save DIR` writes DIR/<type>.npz (image, transmittance, CPU seconds);
`--compare DIR` renders the same skies and compares them with DIR's, over the cloud pixels
(the upper half where either transmittance is below 0.99): the median and 95th percentile
of the per-pixel relative difference of the luminance, the mean relative difference of the
mean radiance over those pixels, the mean and 99th percentile of |delta T|.
`--seed N` sets the march's jitter seed (`clouds.lighting.seed`): a second seed of the same
build is the march's own noise, the floor any change is measured against.
`--lighting JSON` merges more `clouds.lighting` settings, e.g. a shadow ray per sample of
many steps, `{"shadow_grid": false, "light_steps": 64}`: a reference for the grids' error.

    PYTHONPATH=build /usr/bin/python3 bench/clouds/types_images.py --width 1024 --save /tmp/before
    PYTHONPATH=build /usr/bin/python3 bench/clouds/types_images.py --width 1024 --compare /tmp/before
"""

import argparse
import json
import os
import time

import numpy as np

import welkin

LUMA = np.array([0.2126, 0.7152, 0.0722])


def scene(cloud_type, seed, lighting=None):
    return {
        "version": 1,
        "atmosphere": "bruneton2017",
        "sun": {"direction": [0.6, 0.2, 0.5]},
        "clouds": {"layers": [{"cloud_type": cloud_type}], "lighting": {"seed": seed, **(lighting or {})}},
    }


def render(cloud_type, width, seed, lighting=None):
    text = json.dumps(scene(cloud_type, seed, lighting))
    c0 = time.process_time()
    image, t = welkin.scene_sky_image(text, width, sun_disc=False, return_transmittance=True)
    return np.asarray(image, np.float64), np.asarray(t, np.float64), time.process_time() - c0


def compare(a_img, a_t, b_img, b_t):
    h = a_t.shape[0] // 2
    a_img, b_img, a_t, b_t = a_img[:h], b_img[:h], a_t[:h], b_t[:h]
    cloud = (a_t < 0.99) | (b_t < 0.99)
    la, lb = a_img @ LUMA, b_img @ LUMA
    rel = np.abs(lb - la)[cloud] / np.maximum(la[cloud], 1e-12)
    dt = np.abs(b_t - a_t)[cloud]
    return {
        "cloud_px": int(cloud.sum()),
        "median_rel": float(np.median(rel)),
        "p95_rel": float(np.percentile(rel, 95)),
        "mean_rel": float(lb[cloud].mean() / la[cloud].mean() - 1.0),
        "mean_dT": float(dt.mean()),
        "p99_dT": float(np.percentile(dt, 99)),
        "identical": bool(np.array_equal(a_img, b_img) and np.array_equal(a_t, b_t)),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--types", nargs="*", default=list(welkin.CLOUD_TYPES))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--lighting", type=json.loads, default={}, help="more clouds.lighting settings (JSON)")
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--save")
    g.add_argument("--compare")
    args = ap.parse_args()
    if args.save:
        os.makedirs(args.save, exist_ok=True)
    else:
        print(
            "| type | CPU s (this) | CPU s (stored) | cloud pixels | median rel. diff. | p95 rel. diff. "
            "| mean radiance | mean dT | p99 dT | same bits |\n|---|---|---|---|---|---|---|---|---|---|"
        )
    for t in args.types:
        img, tr, cpu = render(t, args.width, args.seed, args.lighting)
        if args.save:
            np.savez_compressed(os.path.join(args.save, f"{t}.npz"), image=img, t=tr, cpu=cpu)
            print(f"{t}: {cpu:.2f} s CPU", flush=True)
            continue
        ref = np.load(os.path.join(args.compare, f"{t}.npz"))
        c = compare(ref["image"], ref["t"], img, tr)
        print(
            f"| {t} | {cpu:.2f} | {float(ref['cpu']):.2f} | {c['cloud_px']} | {100 * c['median_rel']:.2f} % "
            f"| {100 * c['p95_rel']:.1f} % | {100 * c['mean_rel']:+.2f} % | {c['mean_dT']:.4f} "
            f"| {c['p99_dT']:.3f} | {'yes' if c['identical'] else 'no'} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
