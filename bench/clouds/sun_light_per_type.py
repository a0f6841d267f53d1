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
fifth of the cloud's rows), bench/cloud_regions.py; and the median of the
per-pixel ratio's distance from 1.

--boxes does the same for uniform boxes instead of the patches, where the geometry is
known: BOX_HEIGHT_M thick, 2 and 20 times as wide across the sun's azimuth, 4 km long along
it, their base 3 km up, vertical optical depths 1, 3, 10 and 30, the sun 30 degrees up along
the long axis. "below": a fan of rays 20 degrees about the zenith from the ground under the
box's middle (its base; the wide box is a plane-parallel slab there); "side": rays from 3 km
off the long side at the box's mid-height (the side face, parallel to the sun, which only
the light leaking sideways lights). Sums over the rays with reference transmittance < 0.95.

--sky does the same for the two skies' light alone (SKY_ONLY: 1 above the horizon, 0.15
below, no sun), in the side view, the march as it is and with its depths marched per
sample (the zenith's and the nadir's too): what the zenith and nadir grids cost the mix.

--doc replaces the table between "<!-- sun_light_per_type: begin -->" and
"<!-- sun_light_per_type: end -->" in that file ("sun_light_boxes" with --boxes,
"sky_light_per_type" with --sky).
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
from cloud_regions import image_regions  # noqa: E402

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
# --sky: the two skies alone, 1 above the horizon and 0.15 below (a sunlit ground's share);
# the march's own depths marched per sample, the zenith's and nadir's too.
SKY_ONLY = {"sun_irradiance": [0.0], "ambient_radiance": [1.0], "ground_radiance": [0.15]}
SKY_VARIANTS = {
    "as it is": {},
    "depths marched": {"shadow_grid": False, "light_steps": 64, "ambient_steps": 64},
}
BOX_HEIGHT_M = 200.0
BOX_VOXEL_M = 20.0
BOX_TAUS = (1.0, 3.0, 10.0, 30.0)
BOX_WIDTHS = (2.0, 20.0)  # over the height


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


def run(types, variants, paths, voxel, tmp, light=SUN_ONLY, views=VIEWS, log=print):
    """{(type, view): {variant: {region: ratio, region + "_noise": ..., "median_error": ...}}}"""
    out = {}
    atm = welkin.Atmosphere.preset("clear_day")  # not lighting anything: the light is constant
    for cloud_type in types:
        patch = lp.write_patch(welkin, cloud_type, pathlib.Path(tmp) / f"{cloud_type}.vdb", voxel)
        origin, d, right, up = camera(patch)
        mw = np.eye(4)
        mw[:3, 3] = np.asarray(patch.at) - origin  # cloud_radiance's observer is at its origin
        clouds = welkin.VdbClouds(patch.path, density_scale=patch.density_scale, matrix_world=mw)
        for view in views:
            sun = sun_vector(*lp.sun_for(patch, view))
            t0 = time.time()
            refs, alpha = [], 0.0
            for seed in (1, 2):
                L, T, _ = welkin.cloud_radiance(
                    clouds, atm, 0.0, sun, d, method="reference", paths=paths // 2, seed=seed, **light
                )
                refs.append(np.asarray(L)[:, 0].reshape(SIZE[::-1]))
                alpha = alpha + (1.0 - np.asarray(T).reshape(SIZE[::-1])) / 2.0
            ref = (refs[0] + refs[1]) / 2.0
            regs = image_regions(alpha, float(sun @ right), float(sun @ up))
            row = {}
            for name, lighting in variants.items():
                fast = welkin.cloud_radiance(clouds, atm, 0.0, sun, d, lighting=lighting, **light)[0]
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


def box_rays(view, width_m):
    """(origin, (N, 3) directions) of a box view (the header)."""
    if view == "below":
        origin = np.zeros(3)
        a = np.radians(np.linspace(-20.0, 20.0, 9))
        ax, ay = np.meshgrid(a, a)
        d = np.stack([np.sin(ax), np.sin(ay), np.ones_like(ax)], -1)
    else:
        origin = np.array([0.0, -width_m / 2.0 - 3000.0, 3000.0 + BOX_HEIGHT_M / 2.0])
        a, b = np.meshgrid(np.radians(np.linspace(-3.0, 3.0, 9)), np.radians(np.linspace(-1.5, 1.5, 7)))
        d = np.stack([np.sin(a), np.ones_like(a), np.sin(b)], -1)
    d = d.reshape(-1, 3)
    return origin, d / np.linalg.norm(d, axis=-1, keepdims=True)


def run_boxes(variants, paths, tmp, log=print):
    """{(box, view): {variant: {"all": ratio, "all_noise": ...}}} for the uniform boxes."""
    from vdb_dense import write_density

    out = {}
    atm = welkin.Atmosphere.preset("clear_day")
    sun = sun_vector(30.0, 0.0)
    for tau in BOX_TAUS:
        for over in BOX_WIDTHS:
            width = over * BOX_HEIGHT_M
            n = [int(4000.0 / BOX_VOXEL_M), int(width / BOX_VOXEL_M), int(BOX_HEIGHT_M / BOX_VOXEL_M)]
            path = pathlib.Path(tmp) / f"box_{tau:g}_{over:g}.vdb"
            write_density(path, np.ones(n, np.float32), (-n[0] // 2, -n[1] // 2, 0), BOX_VOXEL_M)
            mw = np.eye(4)
            mw[:3, 3] = (0.0, 0.0, 3000.0)
            clouds = welkin.VdbClouds(
                str(path), density_scale=tau / BOX_HEIGHT_M, matrix_world=mw, placement="openvdb"
            )
            name = f"optical depth {tau:g}, {over:g} x as wide"
            for view in ("below", "side"):
                origin, d = box_rays(view, width)
                kw = dict(SUN_ONLY, origin=origin)
                refs, mask = [], None
                for seed in (1, 2):
                    L, T, _ = welkin.cloud_radiance(
                        clouds, atm, 0.0, sun, d, method="reference", paths=paths // 2, seed=seed, **kw
                    )
                    refs.append(np.asarray(L)[:, 0])
                    mask = np.asarray(T) < 0.95 if mask is None else mask & (np.asarray(T) < 0.95)
                ref = (refs[0] + refs[1]) / 2.0
                row = {}
                for vname, lighting in variants.items():
                    fast = np.asarray(
                        welkin.cloud_radiance(clouds, atm, 0.0, sun, d, lighting=lighting, **kw)[0]
                    )
                    f = fast[:, 0][mask].sum()
                    per_seed = [f / x[mask].sum() for x in refs]
                    row[vname] = {
                        "all": float(f / ref[mask].sum()),
                        "all_noise": abs(per_seed[0] - per_seed[1]) / 2,
                    }
                out[(name, view)] = row
                log(f"{name}, {view}: " + "; ".join(f"{k} {c['all']:.3f}" for k, c in row.items()))
    return out


def box_table(results, variants, paths):
    lines = [
        f"Uniform boxes, sun light alone, fast / reference (2 x {paths // 2} paths) over the rays "
        "that meet the box:",
        "",
        "| box | view | " + " | ".join(variants) + " |",
        "|---|---|" + "---|" * len(variants),
    ]
    for (name, view), row in results.items():
        lines.append(
            f"| {name} | {view} | "
            + " | ".join(f"{row[v]['all']:.2f} (±{row[v]['all_noise']:.2f})" for v in variants)
            + " |"
        )
    return "\n".join(lines)


def table(results, variants, paths, voxel, what="Sun light alone"):
    lines = [
        f"{what}, fast / reference (2 x {paths // 2} paths), {SIZE[0]} x {SIZE[1]}, "
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
    p.add_argument("--boxes", action="store_true", help="uniform boxes instead of the patches")
    p.add_argument("--sky", action="store_true", help="the two skies' light alone, side view (SKY_ONLY)")
    p.add_argument("--doc", default="")
    a = p.parse_args()
    variants = dict(SKY_VARIANTS if a.sky else DEFAULT_VARIANTS)
    if a.variant:
        variants = {"as it is": {}}
        for v in a.variant:
            name, _, text = v.partition("=")
            variants[name] = json.loads(text)
    with tempfile.TemporaryDirectory() as tmp:
        if a.boxes:
            text = box_table(run_boxes(variants, a.paths, tmp), variants, a.paths)
        elif a.sky:
            results = run(a.types.split(","), variants, a.paths, a.voxel, tmp, SKY_ONLY, ("side",))
            what = "Sky light alone (1 above the horizon, 0.15 below)"
            text = table(results, variants, a.paths, a.voxel, what)
        else:
            text = table(run(a.types.split(","), variants, a.paths, a.voxel, tmp), variants, a.paths, a.voxel)
    print(text)
    if a.doc:
        doc = pathlib.Path(a.doc)
        marker = "sun_light_boxes" if a.boxes else "sky_light_per_type" if a.sky else "sun_light_per_type"
        begin, end = f"<!-- {marker}: begin -->", f"<!-- {marker}: end -->"
        s = doc.read_text()
        i, j = s.index(begin) + len(begin), s.index(end)
        doc.write_text(s[:i] + "\n" + text + "\n" + s[j:])


if __name__ == "__main__":
    main()
