# SPDX-License-Identifier: Apache-2.0
"""Welkin's cloud lighting against Cycles on one VDB cumulus: accuracy and speed.

    PYTHONPATH=build blender -b --factory-startup --python-use-system-env \
        --python bench/cycles_clouds.py -- [--small 160 90 --samples 1024 --paths 1024] \
        [--full 1920 1080] [--csv bench/results/cycles_clouds.csv]

The scene, the light and how each renderer is set to solve the same problem are in
bench/cycles_volume.py. Two stages, one run:

1. Accuracy, at --small: Cycles (--samples per pixel, seeds 1 and 2), Welkin's reference
   path tracer (--paths per pixel, seeds 1 and 2) and Welkin's fast march, for the same
   pixel rays. On the cloud's pixels (reference opacity 1 - T > 0.05), per-pixel relative
   errors of the radiance: median and 95th percentile of |X - ref| / ref, and the bias of
   the mean (sum(X - ref) / sum(ref)). Cycles against the reference uses the means of the
   two seeds of each; the noise alone gives the same statistics for
   (c1 - c2)/2 - (r1 - r2)/2, which has the variance of that difference but no bias, so the
   two agree within noise when the rows "cycles_vs_reference" and "noise_floor" match.
2. Speed, at --full: Cycles at the sample count whose noise (median relative deviation from
   the reference, extrapolated as 1/sqrt(samples) from stage 1) equals the fast march's
   median error, checked at --small, against the fast march for the same 1920 x 1080 rays
   (the VDB loaded and the rays made inside the timing). Both times are whole calls in the
   same process on the same (shared) machine; the ratio is the figure.
"""

import argparse
import atexit
import math
import os
import shutil
import sys
import tempfile
import time

import bpy  # noqa: F401
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
import cycles_volume as cv  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
p = argparse.ArgumentParser()
p.add_argument("--small", type=int, nargs=2, default=(160, 90))
p.add_argument("--samples", type=int, default=1024, help="Cycles samples per pixel at --small")
p.add_argument("--paths", type=int, default=1024, help="reference paths per pixel at --small")
p.add_argument("--full", type=int, nargs=2, default=(1920, 1080))
p.add_argument("--no-full", action="store_true", help="stage 1 only")
p.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "cycles_clouds.csv"))
p.add_argument("--step-rate", type=float, default=1.0, help="Cycles' volume step rate")
args = p.parse_args(argv)

SIGMA = 0.04  # m^-1 at the densest voxel
SUN = (-0.45, -0.55, 0.70)  # towards the sun: above, behind the camera's left shoulder
E_SUN, L_SKY = 3.0, 0.25  # W m^-2 and W m^-2 sr^-1
CAM, TARGET = (0.0, -1400.0, -60.0), (0.0, 0.0, 0.0)

rows = []


def row(stage, name, value, unit="", note=""):
    rows.append((stage, name, value, unit, note))
    print(f"cycles_clouds: {stage} {name} = {value:.6g} {unit} {note}", flush=True)


def rel_stats(x, ref, mask):
    e = (x - ref)[mask] / ref[mask]
    return (
        float(np.median(np.abs(e))),
        float(np.percentile(np.abs(e), 95)),
        float((x - ref)[mask].sum() / ref[mask].sum()),
    )


def report(stage, name, x, ref, mask, note=""):
    med, p95, bias = rel_stats(x, ref, mask)
    row(stage, f"{name}_median_rel", med, "", note)
    row(stage, f"{name}_p95_rel", p95, "", note)
    row(stage, f"{name}_mean_bias", bias, "", note)
    return med


tmp = tempfile.mkdtemp(prefix="welkin_cycles_clouds_")
atexit.register(shutil.rmtree, tmp, ignore_errors=True)
vdb = os.path.join(tmp, "cumulus.vdb")
cv.write_cumulus(vdb)
light = dict(density_scale=SIGMA, sun_direction=SUN, sun_irradiance=E_SUN, sky_radiance=L_SKY)


def scene_at(size, samples, seed):
    return cv.build_scene(
        vdb,
        camera_location=CAM,
        camera_target=TARGET,
        width=size[0],
        height=size[1],
        samples=samples,
        seed=seed,
        step_rate=args.step_rate,
        **light,
    )


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


# --- Stage 1: accuracy at --small.
small = tuple(args.small)
cyc, t_cyc = [], 0.0
for seed in (1, 2):
    scene = scene_at(small, args.samples, seed)
    img, t = timed(lambda: cv.render(scene, os.path.join(tmp, f"cycles_small_{seed}.exr")))
    cyc.append(img)
    t_cyc += t
ref, t_ref = [], 0.0
for seed in (1, 2):
    out, t = timed(
        lambda: cv.welkin_render(scene, vdb, method="reference", paths=args.paths, seed=seed, **light)
    )
    ref.append(out)
    t_ref += t
(fast_L, fast_T), t_fast = timed(lambda: cv.welkin_render(scene, vdb, method="fast", **light))
c1, c2 = cyc[0][..., 0], cyc[1][..., 0]
r1, r2 = ref[0][0], ref[1][0]
cm, rm = 0.5 * (c1 + c2), 0.5 * (r1 + r2)
t_refm = 0.5 * (ref[0][1] + ref[1][1])
mask = (1.0 - t_refm > 0.05) & (rm > 0)
st = f"{small[0]}x{small[1]}"
row(st, "cloud_pixels", int(mask.sum()), "px")
row(st, "cycles_seconds", t_cyc / 2, "s", f"{args.samples} spp, per render")
row(st, "reference_seconds", t_ref / 2, "s", f"{args.paths} paths, per run")
row(st, "fast_seconds", t_fast, "s")
note = f"Cycles {args.samples} spp x2 seeds vs reference {args.paths} paths x2 seeds"
report(st, "cycles_vs_reference", cm, rm, mask, note)
noise = 0.5 * (c1 - c2) - 0.5 * (r1 - r2)
report(st, "noise_floor", rm + noise, rm, mask, "(c1-c2)/2-(r1-r2)/2: the same statistics from noise alone")
bias_se = float(np.sqrt((noise[mask] ** 2).sum()) / rm[mask].sum())
row(st, "cycles_vs_reference_bias_se", bias_se, "", "standard error of the mean bias")
row(
    st,
    "alpha_max_abs_diff",
    float(np.abs(0.5 * (cyc[0][..., 3] + cyc[1][..., 3]) - (1.0 - t_refm)).max()),
    "",
    "Cycles alpha vs reference 1 - T, all pixels",
)
row(st, "fast_vs_reference_T_max_abs_diff", float(np.abs(fast_T - t_refm).max()), "")
e_fast = report(st, "fast_vs_reference", fast_L, rm, mask)
report(st, "fast_vs_cycles", fast_L, cm, mask)
# Cycles' own noise at --samples: median |c - truth| / truth, one render, from two seeds.
n_cyc = float(np.median(np.abs(c1 - c2)[mask] / (math.sqrt(2.0) * rm[mask])))
n_ref = float(np.median(np.abs(r1 - r2)[mask] / (math.sqrt(2.0) * rm[mask])))
row(st, "cycles_noise_median_rel", n_cyc, "", f"one render at {args.samples} spp")
row(st, "reference_noise_median_rel", n_ref, "", f"one run at {args.paths} paths")
s_match = max(1, int(math.ceil(args.samples * (n_cyc / e_fast) ** 2)))
row(st, "matched_samples", s_match, "spp", "Cycles noise = the fast march's median error")
scene = scene_at(small, s_match, 3)
img = cv.render(scene, os.path.join(tmp, "cycles_small_matched.exr"))
report(st, "cycles_matched_vs_reference", img[..., 0], rm, mask, f"{s_match} spp, seed 3")

# --- Stage 2: speed at --full.
if not args.no_full:
    full = tuple(args.full)
    sf = f"{full[0]}x{full[1]}"
    scene = scene_at(full, s_match, 4)
    img, t_c = timed(lambda: cv.render(scene, os.path.join(tmp, "cycles_full.exr")))
    (fL, fT), t_f = timed(lambda: cv.welkin_render(scene, vdb, method="fast", **light))
    row(sf, "cycles_seconds", t_c, "s", f"{s_match} spp, whole render call")
    row(sf, "fast_seconds", t_f, "s", "VDB load + rays + cloud_radiance")
    row(sf, "cycles_over_fast", t_c / t_f, "x", "target >= 20")
    m = (1.0 - fT > 0.05) & (img[..., 0] > 0)
    report(sf, "fast_vs_cycles", fL, img[..., 0], m, f"Cycles {s_match} spp")
    row(sf, "load_average_1min", os.getloadavg()[0], "")

os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
with open(args.csv, "w") as f:
    f.write("stage,name,value,unit,note\n")
    for r in rows:
        f.write(f'{r[0]},{r[1]},{r[2]:.6g},{r[3]},"{r[4]}"\n')
print(f"cycles_clouds: wrote {args.csv}")
