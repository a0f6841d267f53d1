# SPDX-License-Identifier: Apache-2.0
"""Where the in-frame haze's cost lies: splits each render of bench/cycles_aerial_frame.py
into Cycles' path tracing, the rest of Cycles' render (scene, shader and image sync, the
background's importance map) and what lies outside Cycles (the frame-change handlers with
the table's bake, the compositor, saving the file), from Cycles' own timers.

    BLENDER_USER_SCRIPTS=$(mktemp -d) blender -b --factory-startup --python-use-system-env \
        --debug-cycles --python bench/cycles_aerial_frame.py -- --repeats 41 --markers \
        > /tmp/aerial_frame.log 2>&1
    python3 bench/cycles_log_split.py /tmp/aerial_frame.log [/tmp/another_run.log ...]

Several logs (runs of the same code) are pooled: their repeats together, each still paired
with its own run's "off" render. Each render's figures are Cycles' "Path Tracing" wall time and its "Total render time"
(session.cpp), and the bench's own wall time of the render call (its --markers line, which
follows Cycles' lines for that render). Printed per state: the median over repeats of the
difference to the same repeat's "off" render (--baseline: another state), in ms and as a
share of that render's whole time, and the median ratio with a bootstrap 90 % interval (as
bench/cycles_aerial_frame.py computes it; over pooled runs it sees the repeats' noise, and
the runs' own medians are printed beside it for the noise between runs).
"""

import argparse
import re
import statistics
import sys

import numpy as np

MARKER = re.compile(r"^cycles_aerial_frame: render (\d+) (\S+) wall ([\d.]+) cpu ([\d.]+)")
PATH_TRACING = re.compile(r"^\s*Path Tracing\s+([\d.]+)")
TOTAL = re.compile(r"Total render time: ([\d.]+)")


def renders(lines):
    """(repeat, state) -> {"path": s, "cycles": s, "wall": s}, in the log's order."""
    out, path, total = {}, None, None
    for number, line in enumerate(lines, 1):
        if m := PATH_TRACING.match(line):
            path = float(m.group(1))
        elif m := TOTAL.search(line):
            total = float(m.group(1))
        elif m := MARKER.match(line):
            if path is None or total is None:
                raise SystemExit(
                    f"line {number}: a render without Cycles' timings before it "
                    f"(was Blender run with --debug-cycles?)"
                )
            out[int(m.group(1)), m.group(2)] = {"path": path, "cycles": total, "wall": float(m.group(3))}
            path = total = None
    return out


def bootstrap_interval(ratios, level=0.90, resamples=4000):
    """The central `level` of the medians of `resamples` resamplings of `ratios` (seeded)."""
    medians = np.median(np.random.default_rng(0).choice(ratios, (resamples, ratios.size)), axis=1)
    return tuple(np.quantile(medians, [(1.0 - level) / 2.0, (1.0 + level) / 2.0]))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "log",
        nargs="+",
        help="Blender's output of the bench with --markers and --debug-cycles "
        "(several: runs of the same code, pooled)",
    )
    p.add_argument("--baseline", default="off", help="the state the others are compared with")
    args = p.parse_args()
    base = args.baseline
    r = {}
    for run, log in enumerate(args.log):
        try:
            with open(log, encoding="utf-8", errors="replace") as f:
                r.update({(run, *key): value for key, value in renders(f).items()})
        except OSError as error:
            raise SystemExit(f"log: cannot read {log}: {error.strerror}") from None
    repeats = sorted({(run, k) for run, k, s in r if s == base})
    states = sorted({s for _run, _k, s in r if s != base})
    if not repeats or not states:
        raise SystemExit(
            f"{' '.join(args.log)}: no '{base}' render and other state to compare "
            f"(was the bench run with --markers?)"
        )
    for state in states:
        keys = [(run, k) for run, k in repeats if (run, k, state) in r]
        pairs = [(r[run, k, state], r[run, k, base]) for run, k in keys]
        parts = {
            "path tracing": [a["path"] - b["path"] for a, b in pairs],
            "rest of Cycles' render": [
                (a["cycles"] - a["path"]) - (b["cycles"] - b["path"]) for a, b in pairs
            ],
            "outside Cycles": [(a["wall"] - a["cycles"]) - (b["wall"] - b["cycles"]) for a, b in pairs],
            "whole render": [a["wall"] - b["wall"] for a, b in pairs],
        }
        whole = statistics.median(b["wall"] for _a, b in pairs)
        ratios = np.array([a["wall"] / b["wall"] for a, b in pairs])
        lo, hi = bootstrap_interval(ratios)
        print(
            f"{state} against {base}, {len(pairs)} repeats (medians; {base}'s whole render "
            f"{whole:.3f} s, the median ratio {np.median(ratios):.3f}, 90 % interval "
            f"{lo:.3f}-{hi:.3f}):"
        )
        if len(args.log) > 1:
            runs = [
                np.median([x for (run, _k), x in zip(keys, ratios) if run == n]) for n in range(len(args.log))
            ]
            print("  the runs' own median ratios: " + ", ".join(f"{x:.3f}" for x in runs))
        for name, diffs in parts.items():
            d = statistics.median(diffs)
            print(f"  {name:24s} {1e3 * d:+7.1f} ms  {100.0 * d / whole:+5.1f} %")


if __name__ == "__main__":
    sys.exit(main())
