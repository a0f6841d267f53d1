# SPDX-License-Identifier: Apache-2.0
"""Headless Blender + Cycles: Cycles and Welkin's reference path tracer light the same VDB
cloud alike (the reference validated against an independent renderer).

A ball of constant density (radius 100 m, sigma_t 0.03 m^-1: optical depth 6 through the
centre, so tens of scattering orders matter), written with pyopenvdb, one Henyey-Greenstein
lobe g = 0.6, albedo 1, a sun lamp and a uniform world, seen from 450 m; Cycles (48 x 48,
2 renders of 48 samples, 1024 volume bounces) against welkin.cloud_radiance(method=
"reference", 2 runs of 48 paths) for the same pixel rays and the same light (the set-up and
what is matched: bench/cycles_volume.py). Tolerances come from the noise measured in the
same run, from the two seeds of each renderer:

* the bias of the mean radiance over the cloud's pixels, sum(C - R) / sum(R) of the seed
  means, within 4 of its standard errors (from the seed differences) plus 1 %, an
  allowance for Cycles' ray marching of the volume (voxel-sized steps; measured on 3.4,
  each pixel its centre's ray in both, -0.04 %, se 0.4 %, with the placement the add-on
  uses; the other placement, half a voxel off, gives -1.2 %: this mean hides the shift, the
  per-pixel tests see it);
* the per-pixel median of |C - R| / R within 1.5 x the median that noise alone gives,
  (c1 - c2)/2 - (r1 - r2)/2 (same variance, no bias): a misshapen cloud (a wrong phase)
  fails it;
* Cycles' alpha (1 - T) against the reference's 1 - T: mean difference within 4 standard
  errors plus 0.005 (measured -0.00002, se 0.00026 on 3.4; -0.0014, se 0.0008 on 5.0);
* per-pixel opacity: the RMS of Cycles' alpha - (1 - T) over the pixels where either shows
  cloud (alpha > 0.01) within 1.5 x the RMS that noise alone gives (seed differences);
  measured 0.0180 vs noise 0.0189 on 3.4, 0.0284 vs 0.0301 on 5.0. Cycles' pixel filter is a
  Gaussian of 0.01 px (bench/cycles_volume.py): its box filter is one pixel wide whatever
  its width, which averaged the cloud's edges over the pixel (docs/validation.md, "Cycles'
  pixel filter").

So this validates, against Cycles, the voxel placement the add-on uses on this Blender
(compat.cycles_vdb_placement: "blender" in 3.4-4.5; "openvdb" in 5.0, whose Cycles places
voxels half a voxel away from 4.5's). That it can tell the placements apart is checked
too: the same reference renders with the other placement must FAIL the per-pixel opacity
test (3.4, placement="openvdb": measured RMS 0.153 vs noise
0.020, 7.8 x; its radiance median, 0.104 vs noise 0.077, passes 1.5 x, so it is not used).

Run: PYTHONPATH=build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cycles_clouds.py
"""

import atexit
import os
import pathlib
import shutil
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as T  # noqa: E402
import cycles_volume as cv  # noqa: E402

# `import welkin` (cycles_volume.py) is the installed add-on, which serves the compiled
# module's names (the legacy zip's module, or the Extension's wheel on 4.2+).
T.install_addon()
from welkin.blender import compat  # noqa: E402

# Cycles' voxel placement on this Blender, and the other one, which must fail.
PLACEMENT = compat.cycles_vdb_placement()
OTHER = "openvdb" if PLACEMENT == "blender" else "blender"

SIZE, SAMPLES, PATHS = 48, 48, 48


def main():
    tmp = tempfile.mkdtemp(prefix="welkin_test_cycles_clouds_")
    atexit.register(shutil.rmtree, tmp, ignore_errors=True)
    vdb = os.path.join(tmp, "ball.vdb")
    cv.write_ball(vdb, voxel_m=10.0, radius_m=100.0)
    light = dict(density_scale=0.03, sun_direction=(-0.5, -0.6, 0.62), sun_irradiance=3.0, sky_radiance=0.3)
    cyc, ref, off = [], [], []
    for seed in (1, 2):
        scene = cv.build_scene(
            vdb,
            camera_location=(0.0, -450.0, 0.0),
            camera_target=(0.0, 0.0, 0.0),
            width=SIZE,
            height=SIZE,
            samples=SAMPLES,
            seed=seed,
            **light,
        )
        cyc.append(cv.render(scene, os.path.join(tmp, f"cycles_{seed}.exr")))
        ref.append(
            cv.welkin_render(
                scene, vdb, method="reference", paths=PATHS, seed=seed, placement=PLACEMENT, **light
            )
        )
        off.append(
            cv.welkin_render(scene, vdb, method="reference", paths=PATHS, seed=seed, placement=OTHER, **light)
        )
    c1, c2 = cyc[0][..., 0], cyc[1][..., 0]
    r1, r2 = ref[0][0], ref[1][0]
    cm, rm = 0.5 * (c1 + c2), 0.5 * (r1 + r2)
    alpha_ref = 1.0 - 0.5 * (ref[0][1] + ref[1][1])
    mask = (alpha_ref > 0.05) & (rm > 0.0)
    assert mask.sum() > 0.2 * SIZE * SIZE, f"the cloud covers too few pixels ({mask.sum()})"
    assert np.allclose(cyc[0][..., 0], cyc[0][..., 1]) and np.allclose(cyc[0][..., 0], cyc[0][..., 2]), (
        "grey light"
    )

    noise = 0.5 * (c1 - c2) - 0.5 * (r1 - r2)
    bias = (cm - rm)[mask].sum() / rm[mask].sum()
    bias_se = np.sqrt((noise[mask] ** 2).sum()) / rm[mask].sum()
    print(f"test_cycles_clouds: radiance bias {bias:+.4f} (se {bias_se:.4f}), pixels {mask.sum()}")
    assert abs(bias) < 4.0 * bias_se + 0.01, (
        f"Cycles vs reference: mean radiance bias {bias:+.4f}, se {bias_se:.4f}"
    )

    med = np.median(np.abs(cm - rm)[mask] / rm[mask])
    med_noise = np.median(np.abs(noise)[mask] / rm[mask])
    print(f"test_cycles_clouds: median |C - R| / R {med:.4f}, from noise alone {med_noise:.4f}")
    assert med < 1.5 * med_noise, f"Cycles vs reference per pixel: median {med:.4f} vs noise {med_noise:.4f}"

    # Per-pixel opacity: Cycles' alpha against 1 - T, RMS over the pixels where either shows
    # some cloud, against the RMS of the alpha noise alone (seed differences, as above). The
    # default placement must pass it, OpenVDB's (half a voxel off) must fail it.
    ca = 0.5 * (cyc[0][..., 3] + cyc[1][..., 3])
    nc = 0.5 * (cyc[0][..., 3] - cyc[1][..., 3])
    alphas = {}
    for name, renders in ((PLACEMENT, ref), (OTHER, off)):
        a = 1.0 - 0.5 * (renders[0][1] + renders[1][1])
        n = nc - 0.5 * (renders[1][1] - renders[0][1])
        alphas[name] = a
        edge = (a > 0.01) | (ca > 0.01)
        rms, rms_noise = np.sqrt(((ca - a)[edge] ** 2).mean()), np.sqrt((n[edge] ** 2).mean())
        print(
            f"test_cycles_clouds: placement {name}: alpha RMS difference {rms:.4f}, from noise alone "
            f"{rms_noise:.4f} ({edge.sum()} pixels)"
        )
        if name == PLACEMENT:
            assert rms < 1.5 * rms_noise, (
                f"Cycles alpha vs 1 - T per pixel: RMS {rms:.4f} vs noise {rms_noise:.4f}"
            )
        else:
            assert rms > 1.5 * rms_noise, (
                f"placement={OTHER!r} passes the per-pixel alpha test (RMS {rms:.4f}, "
                f"noise {rms_noise:.4f}): the test cannot see a half-voxel shift"
            )
    o1, o2 = off[0][0], off[1][0]
    om = 0.5 * (o1 + o2)
    mo = mask & (om > 0.0)
    bias_o = (cm - om)[mo].sum() / om[mo].sum()
    print(f"test_cycles_clouds: placement {OTHER}: radiance bias {bias_o:+.4f} (not asserted)")

    a1, a2 = cyc[0][..., 3], cyc[1][..., 3]
    da = (0.5 * (a1 + a2) - alpha_ref)[mask].mean()
    da_se = np.sqrt((((a1 - a2) / 2.0)[mask] ** 2).sum()) / mask.sum()
    print(f"test_cycles_clouds: alpha mean difference {da:+.5f} (se {da_se:.5f})")
    assert abs(da) < 4.0 * da_se + 0.005, f"Cycles alpha vs reference 1 - T: {da:+.5f}, se {da_se:.5f}"
    print("test_cycles_clouds: OK")


main()
