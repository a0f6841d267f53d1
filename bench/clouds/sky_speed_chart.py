# SPDX-License-Identifier: Apache-2.0
"""Speed against error of the cloudy sky's upsampled cloud pass (bench/clouds/bench_clouds.cpp,
"the cloudy sky"): time of a 2048 x 1024 `lut` sky with one default cumulus layer, with every
ray marched (exact) and with the cloud pass upsampled at several settings (CloudUpsampling,
include/welkin/clouds/lighting.hpp), against the error of each against a converged march
(the mean of exact skies with other jitter seeds).

    build/welkin_bench_clouds --sky-only --repeats 3 --csv /tmp/sky.csv
    /usr/bin/python3 bench/clouds/sky_speed_chart.py /tmp/sky.csv
        # -> bench/results/clouds_sky_speed.png + .csv   (Debian's python3-matplotlib)
"""

import csv
import pathlib
import shutil
import sys

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def short(name):
    """A setting's label from its CSV name, cumulus_stride{s}_finest{f}_dT{t}_dL{l}_block{b}."""
    fields = dict(
        part.split("=")
        for part in name.removeprefix("cumulus_")
        .replace("stride", "stride=")
        .replace("_finest", ",finest=")
        .replace("_dT", ",dT=")
        .replace("_dL", ",dL=")
        .replace("_block", ",block=")
        .split(",")
    )
    if fields["stride"] == "1":
        return "exact"
    if fields["dT"] == "1" and fields["dL"] == "1":
        return "no refinement"
    return (
        f"stride {fields['stride'] if fields['stride'] != '0' else 'auto'}, finest {fields['finest']}, "
        f"dT {fields['dT']}, block {float(fields['block']):g} m"
    )


def main():
    src = pathlib.Path(sys.argv[1])
    out = ROOT / "bench" / "results" / "clouds_sky_speed.png"
    rows = [r for r in csv.reader(src.open()) if r and r[0] == "sky" and r[2].startswith("cumulus_stride")]
    if not rows:
        sys.exit(f"{src}: no cumulus_stride rows")
    label = [short(r[2]) for r in rows]
    t = [float(r[3]) for r in rows]
    mean = [100.0 * float(r[9]) for r in rows]  # the mean_error and p99_error columns
    p99 = [100.0 * float(r[10]) for r in rows]
    fig, ax = plt.subplots(figsize=(10, 4.5), dpi=110)
    fig.subplots_adjust(left=0.07, right=0.58, bottom=0.12, top=0.9)
    ax.plot(t, mean, "o", label="mean |error| / mean")
    ax.plot(t, p99, "s", label="99th percentile of the per-pixel error")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax.set_yticks([1, 2, 5, 10, 20, 50])
    for k, (x, y, z) in enumerate(zip(t, mean, p99), start=1):
        ax.annotate(str(k), (x, y), textcoords="offset points", xytext=(4, -10), fontsize=8)
        ax.annotate(str(k), (x, z), textcoords="offset points", xytext=(4, 4), fontsize=8)
    key = "\n".join(f"{k}: {s}" for k, s in enumerate(label, start=1))
    fig.text(0.6, 0.5, key, fontsize=8, va="center", family="monospace")
    ax.set_xlabel("time of the cloudy sky, s (2 cores)")
    ax.set_ylabel("error against a converged march, %")
    ax.set_title("Cloudy sky: upsampled cloud pass, speed against error")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.savefig(out)
    shutil.copy(src, out.with_suffix(".csv"))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
