# SPDX-License-Identifier: Apache-2.0
"""Speed-accuracy chart of the aerial-perspective passes, from `welkin_bench_aerial --csv`.

    build/welkin_bench_aerial --csv aerial.csv
    /usr/bin/python3 bench/plot_aerial.py aerial.csv docs/aerial_chart.png

One point per froxel volume size: time of the whole froxel call (x) against its
in-scattering error relative to the per-pixel march (y: median and 99th percentile), with
the march's own time as a vertical line. Both axes logarithmic.
"""

import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(src, dst):
    rows = list(csv.DictReader(open(src)))
    t = [float(r["total_ms"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    for key, label, marker in (("median_rel_L", "median", "o"), ("p99_rel_L", "99th percentile", "s")):
        ax.plot(t, [100 * float(r[key]) for r in rows], marker=marker, label=f"froxels, {label}")
    for r, x in zip(rows, t):
        ax.annotate(
            f"{r['froxels']}³", (x, 100 * float(r["p99_rel_L"])), textcoords="offset points", xytext=(6, 4)
        )
    march = float(rows[0]["march_ms"])
    ax.axvline(march, color="grey", linestyle="--", label=f"per-pixel march ({march / 1e3:.1f} s)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time for a 1920 x 1080 frame, ms")
    ax.set_ylabel("in-scattering error vs per-pixel march, %")
    ax.set_title("Aerial perspective: froxel volume vs per-pixel march")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(dst)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: plot_aerial.py BENCH.csv OUT.png")
    main(sys.argv[1], sys.argv[2])
