# SPDX-License-Identifier: Apache-2.0
"""The fast cloud march against Welkin's path tracer under the add-on's own default lighting:
the sun and sky of the `bruneton2017` atmosphere (the default preset, four wavelengths) at
sun elevation 35 degrees, not a constant light.

    PYTHONPATH=build /usr/bin/python3 bench/clouds/lighting_vs_reference.py [--paths 1024]
        [--csv bench/results/clouds_lighting.csv] [--plot bench/results/clouds_lighting.png]

Cases (the observer on the ground at the scene origin):
  * "cumulus layer": the default cloud layer (welkin.CloudLayer(): cumulus, the add-on's
    defaults), seen from below: views over a grid of azimuths and elevations 12-60 degrees,
    those the fast march finds cloudy (T < 0.8). From below one sees the layer's shaded
    base: every view is on the shadow side.
  * "VDB cumulus": a lumpy ball of cloud (three overlapping Gaussian blobs, 12 m voxels,
    sigma_t up to 0.03 per m, written here with pyopenvdb) 2.5 km away at right angles to
    the sun's azimuth, so that its sunlit half and its shadow half are both in view: a 9 x 9
    grid of views over it, the cloudy ones (T < 0.8). A view is on the shadow side when the
    point it sees (the transmittance-weighted depth along the view) lies on the far side
    of the cloud's centre from the sun.

Per view: the luminance-like green channel of premultiplied L (the cloud's own light,
comparable between methods: both march the same density in the same air). Figures: the
bias of the mean over the views (fast / reference - 1), the mean absolute relative error
per view, the same two over the shadow-side views, and the reference's own standard error
(from its paths, as a relative error of the mean). Tolerances from the issue: mean within
10 %, shadow side within 15 %.
"""

import argparse
import csv
import math
import pathlib
import sys
import tempfile
import time

import numpy as np

import welkin

SUN_ELEVATION_DEG = 35.0
GREEN = 1  # a middle channel of the default four (560 nm)


def sun_direction():
    e = math.radians(SUN_ELEVATION_DEG)
    return np.array([math.cos(e), 0.0, math.sin(e)])


def directions(azimuths_deg, elevations_deg):
    a, e = np.meshgrid(np.radians(azimuths_deg), np.radians(elevations_deg), indexing="xy")
    return np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=-1).reshape(-1, 3)


def write_vdb_cumulus(path, voxel_m=12.0):
    """Three overlapping Gaussian blobs (a flat-bottomed heap), FloatGrid "density" in 1/m,
    the grid's origin at the heap's centre. Returns its centre (0, 0, 0) in index space."""
    import pyopenvdb as vdb

    n = 64
    i = (np.arange(n) - (n - 1) / 2.0) * voxel_m
    x, y, z = np.meshgrid(i, i, i, indexing="ij")
    d = np.zeros_like(x)
    for (cx, cy, cz), r in (((0, 0, 0), 170.0), ((120, 40, 90), 120.0), ((-110, -30, 60), 110.0)):
        d += np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (2 * r * r))
    d = 0.03 * np.clip(d, 0.0, 1.0) * (z > -150.0)  # a flat base
    grid = vdb.FloatGrid()
    grid.copyFromArray(d.astype(np.float32), ijk=(-(n // 2),) * 3)
    grid.name = "density"
    grid.transform = vdb.createLinearTransform(voxelSize=voxel_m)
    vdb.write(str(path), grids=[grid])


def case_views(clouds, atm, sun, candidates, origin=(0.0, 0.0, 0.0), limit=60):
    L, T, depth = welkin.cloud_radiance(clouds, atm, 0.0, sun, candidates, origin=origin)
    cloudy = np.where(np.asarray(T) < 0.8)[0]
    if len(cloudy) > limit:
        cloudy = cloudy[np.linspace(0, len(cloudy) - 1, limit).astype(int)]
    return candidates[cloudy], np.asarray(depth)[cloudy]


def compare(name, clouds, atm, sun, views, shadow, paths):
    t0 = time.process_time()
    fast, _, _ = welkin.cloud_radiance(clouds, atm, 0.0, sun, views)
    t_fast = time.process_time() - t0
    t0 = time.process_time()
    ref, _, _ = welkin.cloud_radiance(clouds, atm, 0.0, sun, views, method="reference", paths=paths, seed=7)
    t_ref = time.process_time() - t0
    # A second, independent reference run: its difference from the first estimates the noise.
    ref2, _, _ = welkin.cloud_radiance(clouds, atm, 0.0, sun, views, method="reference", paths=paths, seed=8)
    f, r, r2 = (np.asarray(a, np.float64)[:, GREEN] for a in (fast, ref, ref2))
    rel = f / r - 1.0
    noise_view = np.abs(r2 / r - 1.0) / math.sqrt(2.0)  # per view, one run's relative error

    def stats(mask):
        if not mask.any():
            return float("nan"), float("nan")
        return float(f[mask].mean() / r[mask].mean() - 1.0), float(np.abs(rel[mask]).mean())

    bias, mae = stats(np.ones_like(f, bool))
    s_bias, s_mae = stats(shadow)
    row = dict(
        case=name,
        views=len(f),
        shadow_views=int(shadow.sum()),
        bias=bias,
        mean_abs_error=mae,
        shadow_bias=s_bias,
        shadow_mean_abs_error=s_mae,
        reference_noise_per_view=float(np.median(noise_view)),
        paths=paths,
        fast_cpu_s=t_fast,
        reference_cpu_s=t_ref,
    )
    print(
        f"{name}: {len(f)} views ({int(shadow.sum())} on the shadow side): bias {100 * bias:+.1f} %, "
        f"mean |err| {100 * mae:.1f} %; shadow side bias {100 * s_bias:+.1f} %, mean |err| "
        f"{100 * s_mae:.1f} %; reference noise per view (median) {100 * row['reference_noise_per_view']:.1f} %; "
        f"CPU fast {t_fast:.2f} s, reference {t_ref:.1f} s",
        flush=True,
    )
    return row, f, r, shadow


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--paths", type=int, default=1024)
    p.add_argument("--csv")
    p.add_argument("--plot")
    args = p.parse_args()
    atm = welkin.Atmosphere.preset("bruneton2017")
    sun = sun_direction()
    rows, plots = [], []

    layer = welkin.CloudLayer()
    views, _depth = case_views(
        layer, atm, sun, directions(np.arange(0.0, 360.0, 15.0), np.arange(12.0, 61.0, 6.0))
    )
    row, f, r, shadow = compare(
        "cumulus layer (from below)", layer, atm, sun, views, np.ones(len(views), bool), args.paths
    )
    rows.append(row)
    plots.append((row["case"], f, r, shadow))

    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "cumulus.vdb"
        write_vdb_cumulus(path)
        centre = np.array([0.0, 2500.0, 900.0])  # at right angles to the sun's azimuth (+X)
        matrix = np.eye(4)
        matrix[:3, 3] = centre
        vdb_cloud = welkin.VdbClouds(str(path), matrix_world=matrix.tolist(), placement="openvdb")
        to_c = centre / np.linalg.norm(centre)
        right = np.cross(to_c, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, to_c)
        half = math.atan(320.0 / np.linalg.norm(centre))
        s = np.linspace(-half, half, 9)
        grid = np.array([to_c + math.tan(a) * right + math.tan(b) * up for b in s for a in s])
        grid /= np.linalg.norm(grid, axis=1, keepdims=True)
        views, depth = case_views(vdb_cloud, atm, sun, grid)
        seen = views * depth[:, None]  # the point each view sees, from the origin
        shadow = (seen - centre) @ sun < 0.0
        row, f, r, shadow = compare("VDB cumulus (side view)", vdb_cloud, atm, sun, views, shadow, args.paths)
        rows.append(row)
        plots.append((row["case"], f, r, shadow))

    if args.csv:
        with open(args.csv, "w", newline="") as out:
            w = csv.DictWriter(out, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, len(plots), figsize=(5.2 * len(plots), 4.6))
        for ax, (name, f, r, shadow) in zip(np.atleast_1d(axes), plots):
            lim = [0.0, 1.05 * max(f.max(), r.max())]
            ax.plot(lim, lim, "k-", lw=0.8, label="equal")
            ax.fill_between(
                lim, [0.85 * v for v in lim], [1.15 * v for v in lim], color="0.9", label="within 15 %"
            )
            ax.scatter(r[~shadow], f[~shadow], s=14, label="sunlit side")
            ax.scatter(r[shadow], f[shadow], s=14, marker="s", label="shadow side")
            ax.set_xlim(lim)
            ax.set_ylim(lim)
            ax.set_xlabel("reference (path tracer), W m^-2 sr^-1 nm^-1 at 560 nm")
            ax.set_ylabel("fast march")
            ax.set_title(name, fontsize=10)
            ax.legend(fontsize=8)
        fig.suptitle(
            f"Cloud lighting under the atmosphere's sun and sky (bruneton2017, sun "
            f"{SUN_ELEVATION_DEG:.0f} deg up), per view",
            fontsize=10,
        )
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
