# SPDX-License-Identifier: Apache-2.0
"""Where the fast march's light goes wrong, type by type: its sun light alone against Welkin's
reference path tracer, on each type's VDB patch and in the two views of the Cycles chart
(bench/cycles_layer_patches.py), outside Blender, for variants of the march's options.

    PYTHONPATH=build /usr/bin/python3 bench/clouds/sun_light_per_type.py [--paths 384] \\
        [--types cumulus,stratus] [--variant 'name={"sides": false}' ...] [--doc docs/validation.md]

The light is a sun of irradiance 1 and no sky (welkin.cloud_radiance's constant light): with
a uniform sky and albedo 1 the march's sky light is exact (clouds/lighting.hpp, "Sky light"),
so what differs here is the sun's light, single and multiple scattering. The patch, the
camera (a pinhole on the ground 2.2 patch widths away, aimed at the patch's centre, framing
it as the chart's lens does) and the suns of the "side" and "backlit" views are the chart's;
72 x 48 rays. The reference runs twice (seeds 1 and 2, half the paths each); a ratio's
noise (+-) is half the difference between the two seeds' ratios.

Variants are the scene file's clouds.lighting options (docs/pipelines.md), passed as
welkin.cloud_radiance(lighting=...). The defaults compare the march as it is; its depths
marched per sample (no grids, 64 steps: what the grids' interpolation costs); without the
sides' leak (clouds/diffusion.hpp, "The sides"); and both.

Per type, view and variant: the fast march's light over the reference's, summed over the
cloud's pixels (reference alpha > 0.05), the sunlit and shadow halves (split at the median
of the pixels' position along the sun's direction on the image) and the base (the bottom
fifth of the cloud's rows), as bench/cycles_addon_clouds.py's regions; and the median of the
per-pixel ratio's distance from 1.

--doc replaces the table between "<!-- sun_light_per_type: begin -->" and
"<!-- sun_light_per_type: end -->" in that file.
"""

import argparse
import json
import math
import pathlib
import sys
import tempfile
import time

import numpy as np

import welkin

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
import cycles_layer_patches as lp  # noqa: E402

SIZE = (72, 48)
VIEWS = ("side", "backlit")
REGIONS = ("all", "sunlit", "shadow", "base")
DEFAULT_VARIANTS = {
    "as it is": {},
    "depths marched": {"shadow_grid": False, "light_steps": 64},
    "no sides": {"sides": False},
    "depths marched, no sides": {"shadow_grid": False, "light_steps": 64, "sides": False},
}
SUN_ONLY = {"sun_irradiance": [1.0], "ambient_radiance": [0.0]}


def sun_vector(elevation_deg, azimuth_deg):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])


def camera(patch):
    """The chart's camera: origin, (H*W, 3) ray directions row by row from the top, and its
    right and up axes."""
    origin = np.array([0.0, 0.0, lp.CAMERA_Z])
    forward = np.asarray(patch.at) - origin
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    half = 0.55 * lp.PATCH_M / ((lp.CAMERA_DISTANCE - 0.5) * lp.PATCH_M)  # lp.lens_mm's field
    w, h = SIZE
    x = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * half
    y = -((np.arange(h) + 0.5) / h * 2.0 - 1.0) * half * h / w
    xx, yy = np.meshgrid(x, y)
    d = forward + xx[..., None] * right + yy[..., None] * up
    return origin, (d / np.linalg.norm(d, axis=-1, keepdims=True)).reshape(-1, 3), right, up


def regions(alpha, sun, right, up):
    h, w = alpha.shape
    mask = alpha > 0.05
    yy, xx = np.mgrid[0:h, 0:w].astype(float)
    toward = (xx - xx[mask].mean()) * float(sun @ right) - (yy - yy[mask].mean()) * float(sun @ up)
    sunlit = mask & (toward > np.median(toward[mask]))
    rows = np.nonzero(mask.any(axis=1))[0]
    return {
        "all": mask,
        "sunlit": sunlit,
        "shadow": mask & ~sunlit,
        "base": mask & (yy >= rows.min() + 0.8 * (rows.max() - rows.min() + 1)),
    }


def run(types, variants, paths, voxel, tmp, log=print):
    """{(type, view): {variant: {region: ratio, region + "_noise": ..., "median_error": ...}}}"""
    out = {}
    atm = welkin.Atmosphere.preset("clear_day")  # not lighting anything: the light is constant
    for cloud_type in types:
        patch = lp.write_patch(welkin, cloud_type, pathlib.Path(tmp) / f"{cloud_type}.vdb", voxel)
        origin, d, right, up = camera(patch)
        mw = np.eye(4)
        mw[:3, 3] = np.asarray(patch.at) - origin  # cloud_radiance's observer is at its origin
        clouds = welkin.VdbClouds(patch.path, density_scale=patch.density_scale, matrix_world=mw)
        for view in VIEWS:
            sun = sun_vector(*lp.sun_for(patch, view))
            t0 = time.time()
            refs, alpha = [], 0.0
            for seed in (1, 2):
                L, T, _ = welkin.cloud_radiance(
                    clouds, atm, 0.0, sun, d, method="reference", paths=paths // 2, seed=seed, **SUN_ONLY
                )
                refs.append(np.asarray(L)[:, 0].reshape(SIZE[::-1]))
                alpha = alpha + (1.0 - np.asarray(T).reshape(SIZE[::-1])) / 2.0
            ref = (refs[0] + refs[1]) / 2.0
            regs = regions(alpha, sun, right, up)
            row = {}
            for name, lighting in variants.items():
                fast = welkin.cloud_radiance(clouds, atm, 0.0, sun, d, lighting=lighting, **SUN_ONLY)[0]
                fast = np.asarray(fast)[:, 0].reshape(SIZE[::-1])
                cell = {}
                for r in REGIONS:
                    m = regs[r]
                    per_seed = [fast[m].sum() / x[m].sum() for x in refs]
                    cell[r] = float(fast[m].sum() / ref[m].sum())
                    cell[r + "_noise"] = float(abs(per_seed[0] - per_seed[1]) / 2.0)
                m = regs["all"]
                cell["median_error"] = float(np.median(np.abs(fast[m] / np.maximum(ref[m], 1e-12) - 1.0)))
                row[name] = cell
            out[(cloud_type, view)] = row
            log(
                f"{cloud_type} {view}: {int(regs['all'].sum())} cloud pixels, {time.time() - t0:.1f} s; "
                + "; ".join(
                    f"{n} {c['all']:.3f} / {c['sunlit']:.3f} / {c['shadow']:.3f}" for n, c in row.items()
                )
            )
    return out


def table(results, variants, paths, voxel):
    lines = [
        f"Sun light alone, fast / reference (2 x {paths // 2} paths), {SIZE[0]} x {SIZE[1]}, "
        f"{voxel:g} m voxels; all / sunlit / shadow / base, median per-pixel |ratio - 1|:",
        "",
        "| type | view | " + " | ".join(variants) + " |",
        "|---|---|" + "---|" * len(variants),
    ]
    for (cloud_type, view), row in results.items():
        cells = []
        for name in variants:
            c = row[name]
            noise = max(c[r + "_noise"] for r in REGIONS)
            cells.append(
                " / ".join(f"{c[r]:.2f}" for r in REGIONS) + f" (±{noise:.2f}), {c['median_error']:.2f}"
            )
        lines.append(f"| {cloud_type} | {view} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append(
        "Variants (clouds.lighting): " + "; ".join(f"{n}: `{json.dumps(v)}`" for n, v in variants.items())
    )
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--types", default=",".join(welkin.CLOUD_TYPES))
    p.add_argument("--paths", type=int, default=384, help="reference paths per ray, over two seeds")
    p.add_argument("--voxel", type=float, default=40.0, help="the patch's voxel, m (the chart's)")
    p.add_argument(
        "--variant",
        action="append",
        default=[],
        metavar='NAME={"key": value}',
        help="a clouds.lighting variant (repeatable; default: the four above)",
    )
    p.add_argument("--doc", default="")
    a = p.parse_args()
    variants = dict(DEFAULT_VARIANTS)
    if a.variant:
        variants = {"as it is": {}}
        for v in a.variant:
            name, _, text = v.partition("=")
            variants[name] = json.loads(text)
    with tempfile.TemporaryDirectory() as tmp:
        results = run(a.types.split(","), variants, a.paths, a.voxel, tmp)
    text = table(results, variants, a.paths, a.voxel)
    print(text)
    if a.doc:
        doc = pathlib.Path(a.doc)
        begin, end = "<!-- sun_light_per_type: begin -->", "<!-- sun_light_per_type: end -->"
        s = doc.read_text()
        i, j = s.index(begin) + len(begin), s.index(end)
        doc.write_text(s[:i] + "\n" + text + "\n" + s[j:])


if __name__ == "__main__":
    main()
