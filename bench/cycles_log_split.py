"""Where the in-frame haze's cost lies: splits each render of bench/cycles_aerial_frame.py
into Cycles' path tracing, the rest of Cycles' render (scene, shader and image sync, the
background's importance map) and what lies outside Cycles (the frame-change handlers with
the table's bake, the compositor, saving the file), from Cycles' own timers.

    BLENDER_USER_SCRIPTS=$(mktemp -d) blender -b --factory-startup --python-use-system-env \
        --debug-cycles --python bench/cycles_aerial_frame.py -- --repeats 41 --markers \
        > /tmp/aerial_frame.log 2>&1
    python3 bench/cycles_log_split.py /tmp/aerial_frame.log

Each render's figures are Cycles' "Path Tracing" wall time and its "Total render time"
(session.cpp), and the bench's own wall time of the render call (its --markers line, which
follows Cycles' lines for that render). Printed per state: the median over repeats of the
difference to the same repeat's "off" render (--baseline: another state), in ms and as a
share of that render's whole time.
"""
import argparse
import re
import statistics
import sys

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
                raise SystemExit(f"line {number}: a render without Cycles' timings before it "
                                 f"(was Blender run with --debug-cycles?)")
            out[int(m.group(1)), m.group(2)] = {"path": path, "cycles": total,
                                                "wall": float(m.group(3))}
            path = total = None
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("log", help="Blender's output of the bench with --markers and --debug-cycles")
    p.add_argument("--baseline", default="off", help="the state the others are compared with")
    args = p.parse_args()
    base = args.baseline
    try:
        with open(args.log, encoding="utf-8", errors="replace") as f:
            r = renders(f)
    except OSError as error:
        raise SystemExit(f"log: cannot read {args.log}: {error.strerror}") from None
    repeats = sorted({k for k, s in r if s == base})
    states = sorted({s for _k, s in r if s != base})
    if not repeats or not states:
        raise SystemExit(f"{args.log}: no '{base}' render and other state to compare "
                         f"(was the bench run with --markers?)")
    for state in states:
        pairs = [(r[k, state], r[k, base]) for k in repeats if (k, state) in r]
        parts = {
            "path tracing": [a["path"] - b["path"] for a, b in pairs],
            "rest of Cycles' render": [(a["cycles"] - a["path"]) - (b["cycles"] - b["path"])
                                       for a, b in pairs],
            "outside Cycles": [(a["wall"] - a["cycles"]) - (b["wall"] - b["cycles"])
                               for a, b in pairs],
            "whole render": [a["wall"] - b["wall"] for a, b in pairs],
        }
        whole = statistics.median(b["wall"] for _a, b in pairs)
        ratio = statistics.median(a["wall"] / b["wall"] for a, b in pairs)
        print(f"{state} against {base}, {len(pairs)} repeats (medians; {base}'s whole render "
              f"{whole:.3f} s, the median ratio {ratio:.3f}):")
        for name, diffs in parts.items():
            d = statistics.median(diffs)
            print(f"  {name:24s} {1e3 * d:+7.1f} ms  {100.0 * d / whole:+5.1f} %")


if __name__ == "__main__":
    sys.exit(main())
