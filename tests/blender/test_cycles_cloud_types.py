# SPDX-License-Identifier: Apache-2.0
"""Headless Blender 5.0 + Cycles: each procedural cloud type (welkin.CLOUD_TYPES) as a VDB
patch of its layer under the add-on's own sky seen from the cloud's altitude (the world
texture and the sun lamp: the light the cloud gets; bench/cycles_addon_clouds.py,
world_seen_from), Cycles against the engine's cloud pass (the fast march, the air left
out) for the same pixels.

The patch and the views: bench/cycles_layer_patches.py (a 3 km square of the type's preset
layer around its densest column, its own sigma_t sampled into a VDB at 40 m voxels, as the chart;
the camera on the ground 6.6 km away; Welkin's phase 0.8 HG(0.8) + 0.2 HG(-0.3), albedo
1). Cycles 48 x 32, 256 volume bounces, SAMPLES per seed, seeds 1 and 2; a ratio's noise
is half the difference between the ratios to each seed. Per type:

* the same cloud in both: the cloud covers at least 150 pixels, and the mean opacity of
  the fast march and of Cycles over them agree within 0.03 (the march's transmittance is
  within about 0.01 of the path tracer's, docs/validation.md "Clouds against Cycles");
* the comparison resolves its tolerances: each checked ratio's noise is under a third of
  its tolerance;
* "side" (sun 30 degrees up, 60 degrees left of the view), luminance of the fast march over
  Cycles' (seeds' mean): over the cloud's pixels within 10 %, its sunlit and shadow halves
  within 15 % (the issue's tolerances);
* "backlit" (the sun 3 degrees above the patch's near top edge): Cycles shows a silver
  lining (edge over core above 1: the edge pixels' own brightness, L / alpha, over the
  core's, alpha the fast march's opacity for both renderers, as Cycles' film alpha is no
  transmittance at a cloud's thin edge; edge and core relative to the cloud's own opacity
  for a thin cirrus, bench/cycles_layer_patches.py lining_regions), and the fast march's
  edge over core is above 1 and within 15 % of Cycles'; its noise under a third of that.

The fast march's misses are collected and fail the test together (scripts/test_blender.sh
lists this test as a known failure with the measured reason while they stand); the other
checks fail at once. The full chart, with the reference path tracer:
bench/clouds/cycles_types_lighting.py (docs/validation.md, "Each cloud type against
Cycles").

Only on 5.0 (one version keeps it short): Cycles 3.4 lights two Volume Scatter closures as
the sum of their lobes, not their mixture (bench/cycles_volume.py).

Run: bash scripts/test_blender.sh -v 5.0 tests/blender/test_cycles_cloud_types.py
"""

import atexit
import os
import pathlib
import shutil
import sys
import tempfile
import time

import bpy

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as T  # noqa: E402

NAME = "test_cycles_cloud_types"
if bpy.app.version[:2] != (5, 0):
    T.skip(NAME, "the Cycles lighting comparison runs on Blender 5.0 only (its time)")
    sys.exit(0)

addon, native = T.install_addon()
import cycles_layer_patches as lp  # noqa: E402

SIZE, BOUNCES, VOXEL_M = (48, 32), 256, 40.0
# Cycles' samples per seed (after the volume's sync, a few seconds): the shadow half of
# stratocumulus and the backlit view's edge over core, which divides by the dim core, are
# the noisiest figures here (0.048 and 0.09 at 96 samples).
SAMPLES = {"side": 256, "backlit": 256}
TOLERANCES = {"all": 0.10, "sunlit": 0.15, "shadow": 0.15}
LINING_TOLERANCE = 0.15


def main():
    tmp = tempfile.mkdtemp(prefix="welkin_test_cycles_cloud_types_")
    atexit.register(shutil.rmtree, tmp, ignore_errors=True)
    failures = []

    def log(line):
        print(f"{NAME}: {line}", flush=True)

    for t in native.CLOUD_TYPES:
        start = time.time()
        patch = lp.write_patch(native, t, os.path.join(tmp, f"{t}.vdb"), VOXEL_M)
        built = lp.build(T, native, patch, size=SIZE, samples=SAMPLES["side"], bounces=BOUNCES)
        for view in ("side", "backlit"):
            r = lp.compare(
                T,
                native,
                patch,
                built,
                view,
                paths=0,
                samples=SAMPLES[view],
                tmp=tmp,
                log=log,
                world_at_cloud=True,
            )
            T.check(r["pixels"] >= 150, f"{t} {view}: the cloud covers too few pixels ({r['pixels']})")
            da = r["fast_alpha"] - r["alpha"]
            T.check(
                abs(da) < 0.03,
                f"{t} {view}: the fast march and Cycles see different clouds: d alpha {da:+.3f}",
            )
            if view == "side":
                for k, tol in TOLERANCES.items():
                    noise = r["fast_noise"][k]
                    T.check(
                        noise < tol / 3,
                        f"{t} side: the {k} ratio's noise {noise:.3f} does not resolve {tol:.0%}",
                    )
                    if abs(r["fast"][k] - 1.0) > tol:
                        failures.append(f"{t}: fast / Cycles {k} {r['fast'][k]:.3f} (tolerance {tol:.0%})")
                continue
            lc, lf, noise = (r["lining"][k] for k in ("cycles", "fast", "cycles_noise"))
            T.check(lc is not None, f"{t} backlit: no edge or no core pixels")
            T.check(lc > 1.0, f"{t} backlit: Cycles shows no silver lining (edge/core {lc:.3f})")
            T.check(
                noise is not None and noise < LINING_TOLERANCE / 3 * lc,
                f"{t} backlit: Cycles' edge/core noise {noise} does not resolve {LINING_TOLERANCE:.0%}",
            )
            if not (lf is not None and lf > 1.0 and abs(lf / lc - 1.0) < LINING_TOLERANCE):
                failures.append(f"{t}: silver lining edge/core fast {lf} against Cycles {lc:.3f}")
        log(f"{t}: {time.time() - start:.0f} s")
    T.check(not failures, "; ".join(failures))
    T.done(NAME)


main()
