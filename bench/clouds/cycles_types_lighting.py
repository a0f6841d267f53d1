# SPDX-License-Identifier: Apache-2.0
"""Each procedural cloud type under the add-on's own sky: a VDB patch of the layer rendered
by Cycles, by the WELKIN engine's cloud pass (the fast march) and by Welkin's reference
path tracer, for the same pixels, in one Blender process (5.0: Cycles 3.4 lights Welkin's
two-lobe phase wrongly, bench/cycles_volume.py).

    build/venv-bpy-5.0/bin/python tests/blender/bpy_blender.py -b --factory-startup \
        --python-use-system-env --python bench/clouds/cycles_types_lighting.py -- \
        [--types cumulus,stratus] [--size 96 64] [--samples 64] [--bounces 256] \
        [--paths 128] [--voxel 25] [--csv bench/results/cycles_cloud_types.csv] \
        [--doc docs/validation.md] [--world-at-cloud]

The patch, the views and what each renderer gets: bench/cycles_layer_patches.py (over
bench/cycles_addon_clouds.py's scene). Cycles and the reference each run twice (seeds 1
and 2); a ratio's noise is half the difference between the two seeds' ratios. Rows per
type, luminance ratios to Cycles (the seeds' mean) over the cloud's pixels, its sunlit and
shadow halves and its base ("side" view), and the silver lining, edge over core ("backlit"
view), of each renderer.

--doc replaces the table between the markers "<!-- cycles_cloud_types: begin -->" and
"<!-- cycles_cloud_types: end -->" in that file.
"""

import argparse
import atexit
import os
import pathlib
import shutil
import sys
import tempfile
import time

import bpy

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as T  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
p = argparse.ArgumentParser()
p.add_argument("--types", default="", help="comma-separated (default: every type)")
p.add_argument("--size", type=int, nargs=2, default=(96, 64))
p.add_argument("--samples", type=int, default=64, help="Cycles samples per seed")
p.add_argument("--bounces", type=int, default=256)
p.add_argument("--paths", type=int, default=128, help="reference paths per seed (0: no reference)")
p.add_argument("--voxel", type=float, default=25.0, help="the patch's voxel, m")
p.add_argument("--csv", default="")
p.add_argument("--doc", default="")
p.add_argument(
    "--world-at-cloud",
    action="store_true",
    help="Cycles' world seen from each patch's altitude, not from the ground (the fast march and the "
    "reference light the cloud with the sky at its altitude either way)",
)
args = p.parse_args(argv)

addon, native = T.install_addon()
import cycles_layer_patches as lp  # noqa: E402

types = args.types.split(",") if args.types else list(native.CLOUD_TYPES)
tmp = tempfile.mkdtemp(prefix="welkin_cycles_types_lighting_")
atexit.register(shutil.rmtree, tmp, ignore_errors=True)

results = []  # (patch, side, backlit, seconds)
for t in types:
    start = time.time()
    patch = lp.write_patch(native, t, os.path.join(tmp, f"{t}.vdb"), args.voxel)
    print(
        f"{t}: patch around ({patch.column[0]:.0f}, {patch.column[1]:.0f}) m, optical depth {patch.column_tau:.1f}, "
        f"sigma_t up to {patch.density_scale:.4f} /m, {patch.shape} voxels of {args.voxel:g} m",
        flush=True,
    )
    built = lp.build(T, native, patch, size=tuple(args.size), samples=args.samples, bounces=args.bounces)
    side = lp.compare(
        T, native, patch, built, "side", paths=args.paths, tmp=tmp, world_at_cloud=args.world_at_cloud
    )
    backlit = lp.compare(
        T, native, patch, built, "backlit", paths=args.paths, tmp=tmp, world_at_cloud=args.world_at_cloud
    )
    results.append((patch, side, backlit, time.time() - start))


def f3(x):
    return "" if x is None else f"{x:.3f}"


COLS = [f"{w}_{r}" for w in ("fast", "reference") for r in lp.REGIONS] + [
    f"{w}_{r}_noise" for w in ("fast", "reference") for r in lp.REGIONS
]
LINING = ("cycles", "cycles_noise", "fast", "reference")
if args.csv:
    os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
    with open(args.csv, "w") as f:
        f.write(
            "type,column_x_m,column_y_m,column_tau,sigma_max_per_m,side_pixels,side_alpha,"
            + ",".join(COLS)
            + ",backlit_pixels,"
            + ",".join(f"lining_{k}" for k in LINING)
            + "\n"
        )
        for patch, side, backlit, _s in results:
            vals = []
            for c in COLS:
                w, r = c.split("_")[0], c.split("_")[1]
                key = w + ("_noise" if c.endswith("_noise") else "")
                vals.append(f3(side.get(key, {}).get(r)))
            lin = backlit.get("lining", {})
            f.write(
                f"{patch.cloud_type},{patch.column[0]:.0f},{patch.column[1]:.0f},{patch.column_tau:.3f},"
                f"{patch.density_scale:.5f},{side['pixels']},{side['alpha']:.3f},"
                + ",".join(vals)
                + f",{backlit['pixels']},"
                + ",".join(f3(lin.get(k)) for k in LINING)
                + "\n"
            )
    print(f"wrote {args.csv}")


def cell(d, key, r):
    if key not in d:
        return "-"
    return f"{d[key][r]:.2f} ± {d[key + '_noise'][r]:.2f}"


def lining(d, k):
    v = d.get("lining", {}).get(k)
    return "no core" if v is None else f"{v:.2f}"


lines = [
    f"Blender {bpy.app.version_string}, {args.size[0]} x {args.size[1]}, Cycles 2 x {args.samples} spp "
    f"({args.bounces} bounces), reference 2 x {args.paths} paths, {args.voxel:g} m voxels over "
    f"{lp.PATCH_M / 1000:g} km; "
    + ("Cycles' world seen from the patch's altitude; " if args.world_at_cloud else "")
    + "luminance ratios to Cycles (± half the seeds' difference); "
    "silver lining: edge over core in the backlit view:",
    "",
    "| type | patch: optical depth, sigma_t max | fast: all | sunlit | shadow | base "
    "| reference: all | sunlit | shadow | base | edge / core: Cycles | fast | fast / Cycles "
    "| reference / Cycles |",
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
]
for patch, side, backlit, _s in results:
    lc, lf = backlit.get("lining", {}).get("cycles"), backlit.get("lining", {}).get("fast")
    lr = backlit.get("lining", {}).get("reference")
    lines.append(
        f"| {patch.cloud_type} | {patch.column_tau:.1f}, {patch.density_scale:.4f} /m | "
        + " | ".join(cell(side, w, r) for w in ("fast", "reference") for r in lp.REGIONS)
        + f" | {lining(backlit, 'cycles')} ± {f3(backlit.get('lining', {}).get('cycles_noise')) or '-'}"
        + f" | {lining(backlit, 'fast')} | "
        + (f"{lf / lc:.2f}" if lc and lf else "-")
        + " | "
        + (f"{lr / lc:.2f}" if lc and lr else "-")
        + " |"
    )
print("\n".join(lines))
for patch, _side, _backlit, s in results:
    print(f"{patch.cloud_type}: {s:.0f} s")
if args.doc:
    begin, end = "<!-- cycles_cloud_types: begin -->", "<!-- cycles_cloud_types: end -->"
    text = pathlib.Path(args.doc).read_text()
    a, b = text.index(begin) + len(begin), text.index(end)
    pathlib.Path(args.doc).write_text(text[:a] + "\n" + "\n".join(lines) + "\n" + text[b:])
    print(f"wrote the table into {args.doc}")
