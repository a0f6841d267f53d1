# SPDX-License-Identifier: Apache-2.0
"""Error against time for the fast cloud lighting, against the path-tracing reference.

    build/welkin_bench_clouds --csv /tmp/clouds.csv          # the figures (a few minutes)
    /usr/bin/python3 bench/clouds/chart.py /tmp/clouds.csv   # -> bench/results/clouds_chart.png + .csv

One panel per case (thin wispy layer, dense cumulus layer, the VDB ball the benchmark
writes with OpenVDB). x: time per million rays (the fast march timed on 128 x 128 views
of the case's cone; the reference per view, extrapolated); y: the mean absolute error
per view relative to the mean radiance, on 6 x 6 views, against the reference at its
full path count. Lines: the fast march at five quality settings (view + shadow steps)
with the optical-depth grid and the delta-Eddington multiple scattering (the default),
at the defaults with Wrenninge's octaves instead ("octaves", the default before it), the
march before the grid ("legacy", octaves), and the reference at
1/64, 1/16 and 1/4 of its paths (its own noise for its time). The dotted line is the
full reference's standard error: errors below it are not resolved.
"""

import argparse
import csv
import pathlib
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv", help="the CSV written by welkin_bench_clouds --csv")
    ap.add_argument("--out", default=str(ROOT / "bench" / "results"), help="output folder")
    args = ap.parse_args()
    rows = list(csv.DictReader(open(args.csv)))
    cases = [r["name"] for r in rows if r["kind"] == "truth"]
    if not cases:
        print(
            f"{args.csv}: no reference rows (kind 'truth'); run welkin_bench_clouds without --sky-only",
            file=sys.stderr,
        )
        return 1
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        mine = [r for r in rows if r["name"] == case]
        cases_of = [r for r in mine if r["kind"] == "case"]
        fast = [r for r in cases_of if "legacy" not in r["variant"] and "octaves" not in r["variant"]]
        legacy = [r for r in mine if r["kind"] == "case" and "legacy" in r["variant"]]
        octaves = [r for r in mine if r["kind"] == "case" and r["variant"].endswith("octaves")]
        ref = [r for r in mine if r["kind"] == "reference"]
        truth = [r for r in mine if r["kind"] == "truth"][0]
        t = lambda rs: [float(r["time_s"]) for r in rs]  # noqa: E731
        e = lambda rs: [100 * float(r["mean_abs_error"]) for r in rs]  # noqa: E731
        ax.plot(t(fast), e(fast), "o-", color="tab:blue", label="fast march (grid)")
        for r in fast:
            ax.annotate(
                r["variant"].replace("fast ", ""),
                (float(r["time_s"]), 100 * float(r["mean_abs_error"])),
                textcoords="offset points",
                xytext=(4, 4),
                fontsize=7,
            )
        ax.plot(t(octaves), e(octaves), "D", color="tab:green", label="fast march 96+8, Wrenninge octaves")
        ax.plot(t(legacy), e(legacy), "s", color="tab:gray", label="legacy (octaves, shadow ray per sample)")
        ax.plot(t(ref), e(ref), "^-", color="tab:red", label="reference, fewer paths")
        ax.axhline(
            100 * float(truth["mean_abs_error"]), ls=":", color="tab:red", label="reference standard error"
        )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per million rays (s, 2 cores)")
        ax.set_ylabel("mean |error| per view (% of mean radiance)")
        ax.set_title(f"{case} (truth: {truth['paths']} paths)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    png = out / "clouds_chart.png"
    fig.savefig(png, dpi=120)
    dst = out / "clouds_chart.csv"
    if pathlib.Path(args.csv).resolve() != dst.resolve():
        shutil.copyfile(args.csv, dst)
    print(f"wrote {png} and {dst}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
