"""Speed against error of the cloudy sky's upsampled cloud pass (bench/clouds/bench_clouds.cpp,
"the cloudy sky"): time of a 2048 x 1024 `lut` sky with one default cumulus layer, with every
ray marched (exact) and with the cloud pass marched on a coarser grid and upsampled where
smooth, against the error of each against the exact image.

    build/welkin_bench_clouds --sky-only --repeats 1 --csv /tmp/sky.csv
    build/venv-charts/bin/python bench/clouds/sky_speed_chart.py /tmp/sky.csv
        # -> bench/results/clouds_sky_speed.png + .csv   (needs matplotlib)
"""
import csv
import pathlib
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    src = pathlib.Path(sys.argv[1])
    out = ROOT / "bench" / "results" / "clouds_sky_speed.png"
    rows = [r for r in csv.reader(src.open()) if r and r[0] == "sky" and r[2].startswith("cumulus_stride")]
    if not rows:
        sys.exit(f"{src}: no cumulus_stride rows")
    label = [r[2].removeprefix("cumulus_") for r in rows]
    t = [float(r[3]) for r in rows]
    mean = [100.0 * float(r[4] or 0.0) for r in rows]
    p99 = [100.0 * float(r[5] or 0.0) for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4), dpi=110)
    ax.plot(t, mean, "o", label="mean |error| / mean")
    ax.plot(t, p99, "s", label="99th percentile of the per-pixel error")
    for s, x, y in zip(label, t, mean):
        ax.annotate("exact" if s.startswith("stride1_") else s, (x, y), textcoords="offset points",
                    xytext=(4, 6), fontsize=7)
    ax.axvline(2.0, color="grey", lw=0.8, ls=":")
    ax.set_xlabel("time of the cloudy sky, s (2 cores)")
    ax.set_ylabel("error against the exact image, %")
    ax.set_title("Cloudy sky: upsampled cloud pass, speed against error")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out)
    shutil.copy(src, out.with_suffix(".csv"))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
