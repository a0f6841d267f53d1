# SPDX-License-Identifier: Apache-2.0
"""Speed against accuracy: every sky method and setting against the reference.

    PYTHONPATH=build /usr/bin/python3 bench/chart.py            # the full chart (~20 min, 2 cores)
    PYTHONPATH=build /usr/bin/python3 bench/chart.py --quick    # a reduced set, for development

What it does
------------
1. Scenes: sun elevations from -8 to 90 degrees (twilight included) x observer altitudes
   0 m, 1 km, 10 km, 50 km, 100 km, 400 km x the presets `clear_day` (the default),
   `bruneton2017` and `hazy`.
2. Directions: a Fibonacci sphere (the golden-angle spiral) of --directions points over the
   whole sphere, below the horizon too. A 2048x1024 reference sky takes hours; a few
   hundred evenly spread directions estimate the same sphere statistics.
3. Truth: the `reference` path tracer (all orders, ground reflection) at 10 nm spectral
   sampling (360-830 nm), --paths paths per direction, converted to linear Rec.709 through
   CIE 1931. Its own noise is recorded: the standard error of its luminance, bounded above
   by treating the wavelengths as perfectly correlated (every path carries all of them).
4. Candidates: `analytic`; `lut` at three texture sizes; `raymarch` at five step counts;
   and, for the defaults of each, the default 4 wavelengths (620/560/480/440 nm, one SIMD
   batch, converted with the fitted matrices of src/color/color.cpp) against full spectral
   sampling (10 nm). `auto` judges an atmosphere of up to four wavelengths by the default
   rows and a larger one by the spectral rows.
5. Error, per direction, against the reference: the relative luminance error
   |Y - Y_ref| / max(Y_ref, Y_floor), with Y the CIE Y of the Rec.709 colour and
   Y_floor = 1e-3 x the scene's sphere-mean reference luminance (directions into empty
   space, black in both, count as exact rather than 0/0); and CIEDE2000 with the scene
   normalised so that its 95th-percentile reference luminance is the Lab white (Y = 1).
   Statistics over all directions of all scenes: mean, 95th percentile, max.
6. Time: per method and setting, calls with 256 and with 2048*1024 directions (4096 for
   raymarch; 262144 and 1024 for the spectral settings), the faster of repeated runs, on the bruneton2017 preset at the ground with
   the sun 30 degrees up, fitted as fixed (LUT builds) + per-direction x N; a 2048x1024
   HDRI is fixed + 2048*1024 x per-direction. CPU seconds (all threads summed), because
   the wall clock of a shared machine counts other people's work too; wall time is in
   chart.csv as well. The reference's time is measured on the scenes themselves.

Outputs (in --out, default bench/results/):
  chart.csv            one row per method+setting: time and error statistics
  scenes.csv           one row per method+setting+scene: p95/mean/max error, non-finite count
  reference_noise.csv  the reference's relative standard error per scene
  chart.png            log time per HDRI against log error, the Pareto front marked
  stability_<preset>.png  per method+setting, p95 error over (sun elevation, altitude),
                       cells above --tolerance marked, non-finite values crossed, and the
                       reference's own noise
and (full run only, or with --table) the table `auto` chooses from:
  src/sky/auto_table.cpp  (generated; rerun this script to refresh it, then rebuild)
"""

import argparse
import csv
import math
import pathlib
import shutil
import subprocess
import sys
import time

import numpy as np

import welkin

ROOT = pathlib.Path(__file__).resolve().parents[1]

# --- scenes ---------------------------------------------------------------------------
SUN_ELEVATIONS_DEG = [-8.0, -4.0, -2.0, 0.0, 3.0, 10.0, 20.0, 40.0, 65.0, 90.0]
ALTITUDES_M = [0.0, 1e3, 1e4, 5e4, 1e5, 4e5]
PRESETS = ["clear_day", "bruneton2017", "hazy"]
QUICK_SUN_ELEVATIONS_DEG = [-8.0, 0.0, 10.0, 60.0]
QUICK_ALTITUDES_M = [0.0, 1e4, 4e5]

SPECTRAL_STEP_NM = 10.0
HDRI_DIRECTIONS = 2048 * 1024
# The reference is noisiest with the sun below the horizon (light reaches the shadowed air
# only after several scatterings): it gets this many times more paths there.
TWILIGHT_PATH_FACTOR = 4
# Timing: the fastest of this many calls at each size.
TIMING_REPEATS = 4

LUT_SIZES = {
    "small": dict(
        transmittance_width=64,
        transmittance_height=16,
        multiscattering_size=16,
        skyview_width=96,
        skyview_height=54,
    ),
    "default": dict(
        transmittance_width=256,
        transmittance_height=64,
        multiscattering_size=32,
        skyview_width=192,
        skyview_height=108,
    ),
    "large": dict(
        transmittance_width=512,
        transmittance_height=128,
        multiscattering_size=64,
        skyview_width=384,
        skyview_height=216,
    ),
}
RAYMARCH_STEPS = [(8, 4), (16, 8), (32, 16), (64, 32), (128, 64)]


def candidate_settings():
    """(label, method, spectral, keyword options) for every method and setting charted."""
    out = [("analytic", "analytic", False, {})]
    for name, kw in LUT_SIZES.items():
        out.append((f"lut {name}", "lut", False, kw))
    for steps, sun_steps in RAYMARCH_STEPS:
        out.append(
            (f"raymarch {steps}/{sun_steps}", "raymarch", False, dict(steps=steps, sun_steps=sun_steps))
        )
    out.append(("analytic spectral", "analytic", True, {}))
    out.append(("lut default spectral", "lut", True, LUT_SIZES["default"]))
    out.append(("raymarch 64/32 spectral", "raymarch", True, dict(steps=64, sun_steps=32)))
    return out


def fibonacci_sphere(n):
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(1.0 - z * z)
    return np.ascontiguousarray(np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1))


def sun_direction(elevation_deg, azimuth_deg=90.0):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


# --- colour -------------------------------------------------------------------------------
# Linear Rec.709 (D65) to CIE XYZ (ITU-R BT.709 primaries; the Y row is the luminance).
RGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])


def luminance(rgb):
    return rgb @ RGB_TO_XYZ[1]


def ciede2000(rgb, rgb_ref):
    """CIEDE2000 between two linear Rec.709 colour sets of one scene, normalised so the
    reference's 95th-percentile luminance is Lab's white."""
    from skimage.color import deltaE_ciede2000, xyz2lab

    white = float(np.percentile(luminance(rgb_ref), 95))
    if not white > 0.0:
        return np.zeros(len(rgb))
    lab = xyz2lab((np.clip(rgb, 0, None) @ RGB_TO_XYZ.T / white)[None], illuminant="D65")
    lab_ref = xyz2lab((np.clip(rgb_ref, 0, None) @ RGB_TO_XYZ.T / white)[None], illuminant="D65")
    return deltaE_ciede2000(lab_ref, lab)[0]


def relative_luminance_error(y, y_ref):
    floor = 1e-3 * float(np.mean(y_ref))
    denom = np.maximum(y_ref, floor)
    err = np.abs(y - y_ref)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(denom > 0.0, err / np.where(denom > 0, denom, 1.0), np.where(err > 0.0, np.inf, 0.0))
    return rel


# --- evaluation -------------------------------------------------------------------------
class Atmospheres:
    def __init__(self):
        self.cache = {}

    def get(self, preset, spectral):
        key = (preset, spectral)
        if key not in self.cache:
            wl = welkin.spectral_wavelengths_nm(SPECTRAL_STEP_NM) if spectral else None
            self.cache[key] = welkin.Atmosphere.preset(preset, wl)
        return self.cache[key]


def reference_scene(atm, altitude_m, sun, dirs, paths, seed):
    t0 = time.process_time()
    spectra, se = welkin.sky_radiance(
        atm, altitude_m, sun, dirs, method="reference", paths=paths, seed=seed, return_standard_error=True
    )
    seconds = time.process_time() - t0  # CPU seconds, as for the other methods
    wl = atm.wavelengths_nm
    rgb = welkin.spectrum_to_rgb(spectra, wl, -3.0).astype(np.float64)
    # Y is a non-negative weighting of the spectrum, so the Y of the per-wavelength standard
    # errors bounds the standard error of Y from above (perfect correlation).
    se_y = luminance(welkin.spectrum_to_rgb(se, wl, -3.0).astype(np.float64))
    return rgb, se_y, seconds


def time_setting(atms, method, spectral, kw, repeats):
    """(fixed, per direction) cost in CPU seconds and in wall seconds.

    Two sizes, the cheaper of `repeats` runs of each, fitted as fixed + per-direction x N.
    CPU time (all threads of this process summed) is what auto's table uses: on a shared
    machine the wall clock also counts other people's work, CPU time only ours. On an idle
    machine a call's wall time is about its CPU time divided by the cores it keeps busy."""
    atm = atms.get("bruneton2017", spectral)
    sun = sun_direction(30.0)
    small_n = 256
    # Enough directions that the per-direction cost dominates the fixed one.
    large_n = (
        (1024 if spectral else 4096) if method == "raymarch" else (262144 if spectral else HDRI_DIRECTIONS)
    )
    small, large = fibonacci_sphere(small_n), fibonacci_sphere(large_n)
    t_small = [_timed(atm, sun, small, method, kw) for _ in range(repeats)]
    t_large = [_timed(atm, sun, large, method, kw) for _ in range(max(1, repeats - 1))]
    out = []
    for k in (0, 1):  # 0: CPU, 1: wall
        a, b = min(t[k] for t in t_small), min(t[k] for t in t_large)
        per_dir = max(0.0, (b - a) / (large_n - small_n))
        out.append((max(0.0, a - per_dir * small_n), per_dir))
    return out[0], out[1]


def _timed(atm, sun, dirs, method, kw):
    c0, t0 = time.process_time(), time.perf_counter()
    welkin.sky_radiance(atm, 0.0, sun, dirs, method=method, output="rgb", **kw)
    return time.process_time() - c0, time.perf_counter() - t0


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--quick",
        action="store_true",
        help="reduced scene set and fewer paths (development); does not write "
        "the auto table unless --table is given",
    )
    ap.add_argument(
        "--directions",
        type=int,
        default=None,
        help="directions on the Fibonacci sphere (default 160, quick 96)",
    )
    ap.add_argument(
        "--paths",
        type=int,
        default=None,
        help="reference paths per direction with the sun up (default 2048, "
        "quick 1024); TWILIGHT_PATH_FACTOR times more with the sun down",
    )
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument(
        "--tolerance", type=float, default=0.05, help="relative luminance error the stability map marks (p95)"
    )
    ap.add_argument(
        "--out", default=None, help="output folder (default bench/results, quick: bench/results/quick)"
    )
    ap.add_argument(
        "--table", default=None, help="write the auto table here (full run default: src/sky/auto_table.cpp)"
    )
    ap.add_argument("--no-table", action="store_true", help="do not write the auto table")
    ap.add_argument(
        "--replot",
        action="store_true",
        help="only redraw chart.png and stability.png from the CSV files in --out",
    )
    ap.add_argument(
        "--retime",
        action="store_true",
        help="only measure the times again (a few minutes), keep the errors in "
        "--out's CSV files; rewrites chart.csv, the pictures and the table",
    )
    return ap.parse_args()


def measure_scenes(atms, settings, dirs, suns, alts, paths, seed, start):
    """Every preset x altitude x sun: the reference's radiance and noise, and each setting's
    errors against it. Returns (scene rows, noise rows, per-setting errors, reference
    CPU seconds per path)."""
    n_dirs = len(dirs)
    scene_rows, noise_rows = [], []
    per_setting = {label: dict(rel=[], rel_day=[], de=[], nonfinite=0) for label, *_ in settings}
    ref_seconds, ref_evals = 0.0, 0
    for preset in PRESETS:
        for alt in alts:
            for sun_el in suns:
                sun = sun_direction(sun_el)
                scene_paths = paths * (TWILIGHT_PATH_FACTOR if sun_el <= 0 else 1)
                ref_rgb, ref_se_y, secs = reference_scene(
                    atms.get(preset, True), alt, sun, dirs, scene_paths, seed
                )
                ref_seconds += secs
                ref_evals += n_dirs * scene_paths
                y_ref = luminance(ref_rgb)
                floor = 1e-3 * float(np.mean(y_ref))
                noise = ref_se_y / np.maximum(np.maximum(y_ref, floor), 1e-300)
                noise = np.where(ref_se_y > 0, noise, 0.0)
                noise_rows.append(
                    dict(
                        preset=preset,
                        altitude_m=alt,
                        sun_elevation_deg=sun_el,
                        paths=scene_paths,
                        directions=n_dirs,
                        noise_mean=float(np.mean(noise)),
                        noise_p95=float(np.percentile(noise, 95)),
                        noise_max=float(np.max(noise)),
                        reference_seconds=secs,
                    )
                )
                for label, method, spectral, kw in settings:
                    atm = atms.get(preset, spectral)
                    spectra = welkin.sky_radiance(atm, alt, sun, dirs, method=method, **kw)
                    # A failure is a non-finite or negative radiance. (Rec.709 may go
                    # negative for a saturated colour outside its gamut: that is colour,
                    # not failure; the conversion is the one output="rgb" makes.)
                    bad = int(
                        np.count_nonzero(~np.isfinite(spectra))
                        + np.count_nonzero(np.isfinite(spectra) & (spectra < 0))
                    )
                    rgb = welkin.spectrum_to_rgb(spectra, atm.wavelengths_nm, -3.0).astype(np.float64)
                    bad += int(np.count_nonzero(~np.isfinite(rgb)))
                    if bad:
                        rel = np.full(n_dirs, np.inf)
                        de = np.full(n_dirs, np.inf)
                    else:
                        rel = relative_luminance_error(luminance(rgb), y_ref)
                        de = ciede2000(rgb, ref_rgb)
                    acc = per_setting[label]
                    acc["rel"].append(rel)
                    if sun_el > 0:
                        acc["rel_day"].append(rel)
                    acc["de"].append(de)
                    acc["nonfinite"] += bad
                    scene_rows.append(
                        dict(
                            setting=label,
                            method=method,
                            spectral=int(spectral),
                            preset=preset,
                            altitude_m=alt,
                            sun_elevation_deg=sun_el,
                            rel_lum_mean=float(np.mean(rel)),
                            rel_lum_p95=float(np.percentile(rel, 95)),
                            rel_lum_max=float(np.max(rel)),
                            de2000_mean=float(np.mean(de)),
                            de2000_p95=float(np.percentile(de, 95)),
                            nonfinite_or_negative=bad,
                        )
                    )
                print(
                    f"{preset:12s} alt {alt:8.0f} m sun {sun_el:6.1f} deg: reference "
                    f"{secs:5.1f} s, noise p95 {noise_rows[-1]['noise_p95']:.4f}; "
                    f"elapsed {time.perf_counter() - start:6.0f} s",
                    flush=True,
                )

    return scene_rows, noise_rows, per_setting, ref_seconds / ref_evals


def chart_rows_of(settings, per_setting, timing, wall, noise_rows, paths, ref_per_path):
    """One chart row per setting (time against error) and one for the reference's noise."""
    chart_rows = []
    for label, method, spectral, kw in settings:
        acc = per_setting[label]
        rel = np.concatenate(acc["rel"])
        rel_day = np.concatenate(acc["rel_day"])
        de = np.concatenate(acc["de"])
        fixed, per_dir = timing[label]
        hdri = fixed + per_dir * HDRI_DIRECTIONS
        wall_fixed, wall_per_dir = wall[label]
        chart_rows.append(
            dict(
                setting=label,
                method=method,
                spectral=int(spectral),
                options=" ".join(f"{k}={v}" for k, v in kw.items()),
                fixed_cpu_s=fixed,
                per_direction_cpu_s=per_dir,
                hdri_2048x1024_cpu_s=hdri,
                amortised_per_direction_cpu_s=hdri / HDRI_DIRECTIONS,
                hdri_2048x1024_wall_s=wall_fixed + wall_per_dir * HDRI_DIRECTIONS,
                rel_lum_mean=float(np.mean(rel)),
                rel_lum_p95=float(np.percentile(rel, 95)),
                rel_lum_max=float(np.max(rel)),
                rel_lum_mean_sun_up=float(np.mean(rel_day)),
                rel_lum_p95_sun_up=float(np.percentile(rel_day, 95)),
                rel_lum_max_sun_up=float(np.max(rel_day)),
                de2000_mean=float(np.mean(de)),
                de2000_p95=float(np.percentile(de, 95)),
                de2000_max=float(np.max(de)),
                nonfinite_or_negative=acc["nonfinite"],
            )
        )
    noise_all = np.array([r["noise_p95"] for r in noise_rows])
    noise_day = [r for r in noise_rows if r["sun_elevation_deg"] > 0]
    ref_hdri = ref_per_path * paths * HDRI_DIRECTIONS
    chart_rows.append(
        dict(
            setting=f"reference {paths} paths (noise)",
            method="reference",
            spectral=1,
            options=f"paths={paths}",
            fixed_cpu_s=0.0,
            per_direction_cpu_s=ref_per_path * paths,
            hdri_2048x1024_cpu_s=ref_hdri,
            amortised_per_direction_cpu_s=ref_per_path * paths,
            hdri_2048x1024_wall_s=float("nan"),
            rel_lum_mean=float(np.mean([r["noise_mean"] for r in noise_rows])),
            rel_lum_p95=float(np.percentile(noise_all, 95)),
            rel_lum_max=float(np.max([r["noise_max"] for r in noise_rows])),
            rel_lum_mean_sun_up=float(np.mean([r["noise_mean"] for r in noise_day])),
            rel_lum_p95_sun_up=float(np.percentile([r["noise_p95"] for r in noise_day], 95)),
            rel_lum_max_sun_up=float(np.max([r["noise_max"] for r in noise_day])),
            de2000_mean=float("nan"),
            de2000_p95=float("nan"),
            de2000_max=float("nan"),
            nonfinite_or_negative=0,
        )
    )
    return chart_rows


def main():
    args = parse_args()
    if args.replot:
        return replot(pathlib.Path(args.out or (ROOT / "bench/results")), args.tolerance)
    if args.retime:
        return retime(pathlib.Path(args.out or (ROOT / "bench/results")), args)

    n_dirs = args.directions or (96 if args.quick else 160)
    paths = args.paths or (1024 if args.quick else 2048)
    suns = QUICK_SUN_ELEVATIONS_DEG if args.quick else SUN_ELEVATIONS_DEG
    alts = QUICK_ALTITUDES_M if args.quick else ALTITUDES_M
    out = pathlib.Path(args.out or (ROOT / "bench/results" / ("quick" if args.quick else "")))
    out.mkdir(parents=True, exist_ok=True)
    table = None
    if not args.no_table:
        table = args.table or (None if args.quick else str(ROOT / "src/sky/auto_table.cpp"))

    start = time.perf_counter()
    atms = Atmospheres()
    settings = candidate_settings()
    dirs = fibonacci_sphere(n_dirs)

    # Timing first, while nothing else of ours runs.
    timing, wall = {}, {}
    for label, method, spectral, kw in settings:
        timing[label], wall[label] = time_setting(atms, method, spectral, kw, repeats=TIMING_REPEATS)
        print(
            f"time {label:26s} fixed {timing[label][0] * 1e3:8.2f} ms, "
            f"{timing[label][1] * 1e6:8.3f} us/direction CPU; wall {wall[label][0] * 1e3:8.2f} "
            f"ms, {wall[label][1] * 1e6:8.3f} us/direction",
            flush=True,
        )

    scene_rows, noise_rows, per_setting, ref_per_path = measure_scenes(
        atms, settings, dirs, suns, alts, paths, args.seed, start
    )
    chart_rows = chart_rows_of(settings, per_setting, timing, wall, noise_rows, paths, ref_per_path)

    write_csv(out / "chart.csv", chart_rows)
    write_csv(out / "scenes.csv", scene_rows)
    write_csv(out / "reference_noise.csv", noise_rows)
    draw_chart(out / "chart.png", chart_rows, n_dirs, paths, len(noise_rows))
    draw_stability(
        out / "stability.png", scene_rows, noise_rows, [s[0] for s in settings], suns, alts, args.tolerance
    )
    if table:
        write_table(
            pathlib.Path(table),
            settings,
            timing,
            scene_rows,
            noise_rows,
            suns,
            alts,
            paths,
            ref_per_path,
            n_dirs,
        )
        print(f"wrote {table}")
    print(
        f"wrote {out}/chart.csv, scenes.csv, reference_noise.csv, chart.png, stability_*.png "
        f"in {time.perf_counter() - start:.0f} s"
    )


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def pareto(points):
    """Indices of the points no other point beats in both time and error."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def draw_chart(path, rows, n_dirs, paths, n_scenes):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = [r for r in rows if not r["setting"].startswith("reference")]
    noise = [r for r in rows if r["setting"].startswith("reference")][0]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.4))
    colours = {"analytic": "tab:green", "lut": "tab:blue", "raymarch": "tab:orange"}
    for ax, key, name in (
        (axes[0], "rel_lum_p95_sun_up", "relative luminance error, p95, sun above the horizon"),
        (axes[1], "rel_lum_p95", "relative luminance error, p95, all scenes (twilight too)"),
    ):
        pts = [(r["hdri_2048x1024_cpu_s"], r[key]) for r in methods]
        front = pareto(pts)
        for r in methods:
            ax.scatter(
                r["hdri_2048x1024_cpu_s"],
                r[key],
                color=colours[r["method"]],
                marker="s" if r["spectral"] else "o",
                s=46,
                zorder=3,
            )
            ax.annotate(
                r["setting"],
                (r["hdri_2048x1024_cpu_s"], r[key]),
                fontsize=7,
                xytext=(4, 3),
                textcoords="offset points",
            )
        fx = [pts[i][0] for i in front]
        fy = [pts[i][1] for i in front]
        ax.step(fx, fy, where="post", color="k", lw=1, ls="--", zorder=2, label="Pareto front")
        ax.scatter(fx, fy, facecolors="none", edgecolors="k", s=140, zorder=4)
        ax.axhline(
            noise[key],
            color="tab:red",
            lw=1,
            label=f"reference's own noise (standard error), {noise[key]:.2%}",
        )
        ax.scatter(
            noise["hdri_2048x1024_cpu_s"],
            noise[key],
            color="tab:red",
            marker="*",
            s=90,
            zorder=3,
            label=f"reference, {paths} paths (x{TWILIGHT_PATH_FACTOR} with the sun down)",
        )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time for a 2048x1024 HDRI, s (all threads summed)")
        ax.set_ylabel(name)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    dirs_text = f"{n_dirs} directions each" if n_dirs else "directions"
    fig.suptitle(
        f"Welkin sky methods against the spectral reference: {n_scenes} scenes, "
        f"{dirs_text} over the whole sphere (circles the default 4 wavelengths, "
        f"squares spectral)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def read_csv(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            out = {}
            for k, v in r.items():
                try:
                    out[k] = int(v)
                except ValueError:
                    try:
                        out[k] = float(v)
                    except ValueError:
                        out[k] = v
            rows.append(out)
    return rows


def retime(out, args):
    chart_rows = read_csv(out / "chart.csv")
    scene_rows = read_csv(out / "scenes.csv")
    noise_rows = read_csv(out / "reference_noise.csv")
    for r in scene_rows + noise_rows:
        r["sun_elevation_deg"], r["altitude_m"] = float(r["sun_elevation_deg"]), float(r["altitude_m"])
    settings = candidate_settings()
    by_label = {r["setting"]: r for r in chart_rows}
    missing = [label for label, *_ in settings if label not in by_label]
    if missing:
        raise SystemExit(f"chart.csv lacks {missing}: run the full chart")
    atms = Atmospheres()
    timing = {}
    for label, method, spectral, kw in settings:
        (fixed, per_dir), (wall_fixed, wall_per_dir) = time_setting(
            atms, method, spectral, kw, TIMING_REPEATS
        )
        timing[label] = (fixed, per_dir)
        hdri = fixed + per_dir * HDRI_DIRECTIONS
        by_label[label].update(
            fixed_cpu_s=fixed,
            per_direction_cpu_s=per_dir,
            hdri_2048x1024_cpu_s=hdri,
            amortised_per_direction_cpu_s=hdri / HDRI_DIRECTIONS,
            hdri_2048x1024_wall_s=wall_fixed + wall_per_dir * HDRI_DIRECTIONS,
        )
        print(
            f"time {label:26s} fixed {fixed * 1e3:8.2f} ms, {per_dir * 1e6:8.3f} us/direction CPU", flush=True
        )
    write_csv(out / "chart.csv", chart_rows)
    replot(out, args.tolerance)
    if not args.no_table:
        ref = [r for r in chart_rows if r["method"] == "reference"][0]
        paths = int(min(r["paths"] for r in noise_rows))
        suns = sorted({r["sun_elevation_deg"] for r in noise_rows})
        alts = sorted({r["altitude_m"] for r in noise_rows})
        table = pathlib.Path(args.table or (ROOT / "src/sky/auto_table.cpp"))
        write_table(
            table,
            settings,
            timing,
            scene_rows,
            noise_rows,
            suns,
            alts,
            paths,
            ref["per_direction_cpu_s"] / paths,
            args.directions or 160,
        )
        print(f"wrote {table}")


def replot(out, tolerance):
    chart_rows = read_csv(out / "chart.csv")
    scene_rows = read_csv(out / "scenes.csv")
    noise_rows = read_csv(out / "reference_noise.csv")
    labels = list(dict.fromkeys(r["setting"] for r in scene_rows))
    suns = sorted({float(r["sun_elevation_deg"]) for r in noise_rows})
    alts = sorted({float(r["altitude_m"]) for r in noise_rows})
    for r in scene_rows + noise_rows:
        r["sun_elevation_deg"], r["altitude_m"] = float(r["sun_elevation_deg"]), float(r["altitude_m"])
    n_dirs = noise_rows[0].get("directions")
    paths = int(min(r["paths"] for r in noise_rows))
    draw_chart(out / "chart.png", chart_rows, n_dirs, paths, len(noise_rows))
    draw_stability(out / "stability.png", scene_rows, noise_rows, labels, suns, alts, tolerance)
    print(f"redrew {out}/chart.png, stability_*.png")


def draw_stability(path, scene_rows, noise_rows, labels, suns, alts, tolerance):
    """One map per preset: stability_<preset>.png next to `path`."""
    for preset in PRESETS:
        draw_stability_preset(
            path.with_name(f"{path.stem}_{preset}{path.suffix}"),
            [r for r in scene_rows if r["preset"] == preset],
            [r for r in noise_rows if r["preset"] == preset],
            labels,
            suns,
            alts,
            tolerance,
            preset,
        )


def draw_stability_preset(path, scene_rows, noise_rows, labels, suns, alts, tolerance, preset):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    cols = 4
    panels = labels + ["reference's own noise"]
    rows_n = math.ceil(len(panels) / cols)
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.0 * cols, 3.0 * rows_n), squeeze=False)
    norm = LogNorm(vmin=1e-3, vmax=1.0)
    im = None
    for k, label in enumerate(panels):
        ax = axes[k // cols][k % cols]
        grid = np.zeros((len(alts), len(suns)))
        bad = np.zeros_like(grid, dtype=bool)
        if label == panels[-1]:
            for r in noise_rows:
                i, j = alts.index(r["altitude_m"]), suns.index(r["sun_elevation_deg"])
                grid[i, j] = max(grid[i, j], r["noise_p95"])
        for r in scene_rows:
            if r["setting"] != label:
                continue
            i, j = alts.index(r["altitude_m"]), suns.index(r["sun_elevation_deg"])
            grid[i, j] = max(grid[i, j], r["rel_lum_p95"])
            bad[i, j] |= r["nonfinite_or_negative"] > 0
        shown = np.where(np.isfinite(grid), np.clip(grid, 1e-3, 1.0), 1.0)
        im = ax.imshow(shown, origin="lower", cmap="viridis", norm=norm, aspect="auto")
        for i in range(len(alts)):
            for j in range(len(suns)):
                if bad[i, j]:
                    ax.text(j, i, "X", ha="center", va="center", color="red", fontsize=11, weight="bold")
                    continue
                if grid[i, j] > tolerance:
                    ax.add_patch(
                        plt.Rectangle((j - 0.5, i - 0.5), 0.96, 0.96, fill=False, edgecolor="red", lw=1.2)
                    )
                v = grid[i, j]
                text = ">999%" if v >= 10 else (f"{v:.0%}" if v >= 0.01 else f"{v:.1%}")
                ax.text(
                    j, i, text, ha="center", va="center", fontsize=5, color="black" if v > 0.03 else "white"
                )
        ax.set_xticks(range(len(suns)))
        ax.set_xticklabels([f"{s:g}" for s in suns], fontsize=6)
        ax.set_yticks(range(len(alts)))
        ax.set_yticklabels([f"{a / 1e3:g} km" for a in alts], fontsize=6)
        ax.set_title(label, fontsize=8)
        if k % cols == 0:
            ax.set_ylabel("altitude")
        if k // cols == rows_n - 1:
            ax.set_xlabel("sun elevation, deg")
    for k in range(len(panels), rows_n * cols):
        axes[k // cols][k % cols].axis("off")
    fig.colorbar(im, ax=axes, shrink=0.8, label="relative luminance error, p95 over the sphere")
    fig.suptitle(
        f"Stability map, preset {preset}: red frame = p95 error above "
        f"{tolerance:.0%}, red X = a non-finite or negative value",
        fontsize=9,
    )
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_table(path, settings, timing, scene_rows, noise_rows, suns, alts, paths, ref_per_path, n_dirs):
    """The C++ table `auto` chooses from (src/sky/auto.cpp reads it through
    include/welkin/sky/auto_table.hpp)."""

    def opt(kw, key, default):
        return int(kw.get(key, default))

    lines = [
        "// SPDX-License-Identifier: Apache-2.0",
        "// GENERATED by bench/chart.py from its measurements; do not edit by hand.",
        "// Regenerate: PYTHONPATH=build /usr/bin/python3 bench/chart.py (then rebuild).",
        f"// {len(noise_rows)} scenes x {n_dirs} directions, reference {paths} paths at "
        f"{SPECTRAL_STEP_NM:g} nm; measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}.",
        '#include "welkin/sky/auto_table.hpp"',
        "",
        "namespace welkin::auto_table {",
        "namespace {",
        "",
        "constexpr double kAltitudes[] = {" + ", ".join(f"{a:.1f}" for a in alts) + "};",
        "constexpr double kSunElevations[] = {" + ", ".join(f"{s:.1f}" for s in suns) + "};",
        "constexpr const char* kPresets[] = {" + ", ".join(f'"{p}"' for p in PRESETS) + "};",
        "",
        "// method, spectral, transmittance w/h, multiscattering, sky-view w/h, raymarch",
        "// steps/sun steps, fixed CPU s, CPU s per direction",
        "constexpr Setting kSettings[] = {",
    ]
    d = LUT_SIZES["default"]
    for label, method, spectral, kw in settings:
        fixed, per_dir = timing[label]
        lines.append(
            f'    {{"{method}", {str(spectral).lower()}, '
            f"{opt(kw, 'transmittance_width', d['transmittance_width'])}, "
            f"{opt(kw, 'transmittance_height', d['transmittance_height'])}, "
            f"{opt(kw, 'multiscattering_size', d['multiscattering_size'])}, "
            f"{opt(kw, 'skyview_width', d['skyview_width'])}, "
            f"{opt(kw, 'skyview_height', d['skyview_height'])}, "
            f"{opt(kw, 'steps', 64)}, {opt(kw, 'sun_steps', 32)}, "
            f"{fixed:.6g}, {per_dir:.6g}}},  // {label}"
        )
    lines += [
        "};",
        "",
        "// p95 relative luminance error over the sphere, [preset][setting][altitude]"
        "[sun elevation]; infinity where a value was non-finite or negative.",
        f"constexpr double kP95[{len(PRESETS)}][{len(settings)}][{len(alts)}][{len(suns)}] = {{",
    ]
    index = {(r["preset"], r["setting"], r["altitude_m"], r["sun_elevation_deg"]): r for r in scene_rows}

    def num(v):
        return "kInf" if not math.isfinite(v) or v > 1e30 else f"{v:.4g}"

    for p in PRESETS:
        lines.append("    {")
        for label, *_ in settings:
            lines.append(f"        {{  // {label}")
            for a in alts:
                vals = []
                for s in suns:
                    r = index[(p, label, a, s)]
                    v = math.inf if r["nonfinite_or_negative"] else r["rel_lum_p95"]
                    vals.append(num(v))
                lines.append("            {" + ", ".join(vals) + "},")
            lines.append("        },")
        lines.append("    },")
    lines += [
        "};",
        "",
        "// The reference's p95 relative standard error at kReferencePaths paths, "
        "[preset][altitude][sun elevation].",
        f"constexpr double kReferenceNoise[{len(PRESETS)}][{len(alts)}][{len(suns)}] = {{",
    ]
    nindex = {(r["preset"], r["altitude_m"], r["sun_elevation_deg"]): r for r in noise_rows}
    for p in PRESETS:
        lines.append("    {")
        for a in alts:
            lines.append("        {" + ", ".join(num(nindex[(p, a, s)]["noise_p95"]) for s in suns) + "},")
        lines.append("    },")
    lines += [
        "};",
        "",
        "}  // namespace",
        "",
        "const Table& table() {",
        "    static const Table t{kAltitudes, kSunElevations, kPresets, kSettings,",
        "                         &kP95[0][0][0][0], &kReferenceNoise[0][0][0],",
        f"                         {paths}, {ref_per_path:.6g}}};",
        "    return t;",
        "}",
        "",
        "}  // namespace welkin::auto_table",
        "",
    ]
    path.write_text("\n".join(lines))
    # In the repository's format (.clang-format), which scripts/lint.sh checks.
    if shutil.which("clang-format"):
        subprocess.run(["clang-format", "-i", str(path)], check=True)


if __name__ == "__main__":
    sys.exit(main())
