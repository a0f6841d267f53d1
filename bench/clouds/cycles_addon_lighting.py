# SPDX-License-Identifier: Apache-2.0
"""A VDB cumulus under the add-on's own sky: Cycles against the WELKIN engine's cloud pass,
Welkin's reference path tracer, and the pieces between them, in one Blender process.

    build/venv-bpy-5.0/bin/python tests/blender/bpy_blender.py -b --factory-startup \
        --python-use-system-env --python bench/clouds/cycles_addon_lighting.py -- \
        [--size 96 64] [--samples 128] [--bounces 256] [--paths 256] [--lobes welkin|one] \
        [--lamp ground|cloud|both] [--csv bench/results/cycles_addon_clouds.csv] \
        [--doc docs/validation.md] [--world-at-cloud]

--world-at-cloud (with --lamp cloud): Cycles' world is the sky seen from the cloud's
altitude, not from the ground (bench/cycles_addon_clouds.py, world_seen_from). (Blender 3.4: PYTHONPATH=build blender -b --factory-startup --python-use-system-env
--python bench/clouds/cycles_addon_lighting.py -- --lobes one: its Cycles lights two Volume
Scatter closures as the sum of their lobes.) The scene and what each renderer gets:
bench/cycles_addon_clouds.py; the "side" view of tests/blender/test_cycles_clouds_lighting.py
(the sun 30 degrees up, 60 degrees left of the view) and its "backlit" view for the silver
lining. Rows, luminance ratios per region (Cycles' alpha > 0.05; sunlit / shadow halves
towards / away from the sun on the image; base: the bottom fifth of the cloud's rows):

* engine / Cycles: the engine's pass as it renders (the air in front of the cloud included);
* engine without air / Cycles: the pass with the air left out (Cycles has none);
* reference / Cycles: Welkin's path tracer (same light as the engine);
* engine without air / reference.

--doc replaces the table between the markers "<!-- cycles_addon_clouds: begin -->" and
"<!-- cycles_addon_clouds: end -->" in that file.
"""

import argparse
import atexit
import contextlib
import os
import pathlib
import shutil
import sys
import tempfile

import bpy

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as T  # noqa: E402

# Blender's command line passes the script's arguments after "--"; tests/blender/bpy_blender.py
# (PyPI's bpy) passes them alone.
argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
p = argparse.ArgumentParser()
p.add_argument("--size", type=int, nargs=2, default=(96, 64))
p.add_argument("--samples", type=int, default=128)
p.add_argument("--bounces", type=int, default=256)
p.add_argument("--paths", type=int, default=256)
p.add_argument("--sigma", type=float, default=0.04 / 2.7, help="sigma_t at the densest voxel, m^-1")
p.add_argument("--lobes", default="welkin", choices=("welkin", "one"))
p.add_argument("--lamp", default="both", choices=("ground", "cloud", "both"))
p.add_argument("--csv", default="")
p.add_argument("--doc", default="")
p.add_argument("--world-at-cloud", action="store_true", help="Cycles' world seen from the cloud's altitude")
args = p.parse_args(argv)
if args.world_at_cloud and args.lamp != "cloud":
    # Raising the world's altitude re-syncs a synced lamp there too: a "ground" row would not
    # be the lamp at the ground (bench/cycles_addon_clouds.py, world_seen_from).
    p.error("--world-at-cloud needs --lamp cloud")

addon, native = T.install_addon()
import cycles_addon_clouds as ac  # noqa: E402
import cycles_volume as cv  # noqa: E402

LOBES = ac.WELKIN_LOBES if args.lobes == "welkin" else ac.ONE_LOBE
VIEWS = {"side": (30.0, 60.0), "backlit": (43.0, 3.0)}
tmp = tempfile.mkdtemp(prefix="welkin_cycles_addon_lighting_")
atexit.register(shutil.rmtree, tmp, ignore_errors=True)
vdb = os.path.join(tmp, "cumulus.vdb")
ac.write_cloud(vdb)

rows = []  # (view, lamp, comparison, {region: ratio})
lining = []  # (lamp, Cycles edge/core, engine edge/core)
lamps = ("ground", "cloud") if args.lamp == "both" else (args.lamp,)
for lamp in lamps:
    for view, (el, az) in VIEWS.items():
        scene, sun, _ob = ac.build(
            T,
            vdb,
            sigma=args.sigma,
            lobes=LOBES,
            sun_elevation_deg=el,
            sun_azimuth_deg=az,
            camera=(0.0, 0.0, 1.5),
            lens_mm=150.0,
            size=tuple(args.size),
            samples=args.samples,
            bounces=args.bounces,
        )
        e_ground, e_cloud = ac.update_sky(scene, sun, native, lamp=lamp)
        with ac.world_seen_from(scene, ac.CLOUD_AT[2]) if args.world_at_cloud else contextlib.nullcontext():
            cyc = cv.render(scene, os.path.join(tmp, f"cycles_{lamp}_{view}.exr"))
        eng = ac.engine_pass(scene, native, LOBES, air=True)
        noair = ac.engine_pass(scene, native, LOBES, air=False)
        regs = ac.regions(scene, cyc[..., 3], ac.sun_direction(el, az))
        print(
            f"{view}, lamp at the {lamp}: {int(regs['all'].sum())} cloud pixels; the sun's luminance "
            f"at the ground / at the cloud {(e_ground @ ac.LUMINANCE) / (e_cloud @ ac.LUMINANCE):.3f}",
            flush=True,
        )
        if view == "backlit":
            lining.append(
                (
                    lamp,
                    ac.edge_over_core(cyc, regs, cyc[..., 3]),
                    ac.edge_over_core(noair, regs, noair[..., 3]),
                )
            )
            print(f"  silver lining, edge over core: Cycles {lining[-1][1]:.3f}, engine {lining[-1][2]:.3f}")
            continue
        comps = [("engine / Cycles", eng, cyc), ("engine without air / Cycles", noair, cyc)]
        if args.paths:
            ref, _t = ac.reference(scene, native, vdb, args.sigma, LOBES, args.paths)
            comps += [("reference / Cycles", ref, cyc), ("engine without air / reference", noair, ref)]
        for name, x, y in comps:
            r = ac.ratios(x, y, regs)
            rows.append((view, lamp, name, r))
            print(f"  {name}: " + ", ".join(f"{k} {v:.3f}" for k, v in r.items()), flush=True)

KEYS = ("all", "sunlit", "shadow", "base", "p10", "p50", "p90")
if args.csv:
    os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
    with open(args.csv, "w") as f:
        f.write("view,lamp,comparison," + ",".join(KEYS) + "\n")
        for view, lamp, name, r in rows:
            f.write(f"{view},{lamp},{name}," + ",".join(f"{r[k]:.4f}" for k in KEYS) + "\n")
        for lamp, c, e in lining:
            f.write(f"backlit,{lamp},edge over core Cycles {c:.4f} engine {e:.4f}" + "," * len(KEYS) + "\n")
    print(f"wrote {args.csv}")
if args.doc:
    lines = [
        f"Blender {bpy.app.version_string}, {args.size[0]} x {args.size[1]}, Cycles {args.samples} spp "
        f"({args.bounces} bounces), reference {args.paths} paths, "
        + ("Cycles' world seen from the cloud's altitude, " if args.world_at_cloud else "")
        + "phase "
        + ("Welkin's two lobes" if args.lobes == "welkin" else f"one HG lobe g = {cv.G}")
        + "; luminance ratios:",
        "",
        "| lamp | comparison | all | sunlit half | shadow half | base | p10 | p50 | p90 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for _view, lamp, name, r in rows:
        lines.append(f"| {lamp} | {name} | " + " | ".join(f"{r[k]:.3f}" for k in KEYS) + " |")
    for lamp, c, e in lining:
        lines.append(
            f"| {lamp} | silver lining (backlit), edge over core: Cycles {c:.2f}, engine {e:.2f} |" + " |" * 7
        )
    begin, end = "<!-- cycles_addon_clouds: begin -->", "<!-- cycles_addon_clouds: end -->"
    text = pathlib.Path(args.doc).read_text()
    a, b = text.index(begin) + len(begin), text.index(end)
    pathlib.Path(args.doc).write_text(text[:a] + "\n" + "\n".join(lines) + "\n" + text[b:])
    print(f"wrote the table into {args.doc}")
