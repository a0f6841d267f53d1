# SPDX-License-Identifier: Apache-2.0
"""The aerial demo frame at 1920 x 1080: Cycles against Welkin's aerial passes and
against Welkin's own plate of the same world, one Blender process, one run.

    PYTHONPATH=build blender -b --factory-startup --python-use-system-env \
        --python bench/cycles_aerial.py -- [--size 1920] [--samples 16] \
        [--csv bench/results/cycles_aerial.csv]

1. blend/make_aerial_demo.py builds the demo (ground and blocks to 40 km, `hazy`, the Welkin
   world texture) at --size and renders it once with the add-on's aerial perspective on, which
   leaves the frame's scene JSON and its render + Z pass EXR (docs/artists.md "Aerial perspective in
   Blender"); the whole script is timed as "demo_script_total".
2. the same frame rendered by Cycles alone (aerial perspective off: the render call,
   scene sync and BVH included), against, for the same frame's passes:
   `welkin aerial --scene ... --depth ...` (the CLI: LUTs, EXR read, froxels, write) and
   welkin.aerial_perspective(scene, depth) in process (LUTs, froxel build and per-pixel
   application; no file I/O), method froxel (32^3), and raymarch for scale.
3. the same camera and world: the Welkin render engine (`WELKIN`, the render call:
   plate computed by the core and handed to Blender) and `welkin plate --scene` (CLI),
   against Cycles rendering the same world (the meshes hidden from the render, so both
   show sky and sun over the world's own ground) at 1 sample per pixel -- a camera ray that
   meets only the world texture has no noise to average, so one sample is already
   comparable noise -- and at --samples.
All times are the median of --repeats whole calls (1 by default) on this shared 2-core
machine, measured in the same run; the ratios are the figures.
"""

import argparse
import atexit
import os
import runpy
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
p = argparse.ArgumentParser()
p.add_argument("--size", type=int, default=1920)
p.add_argument("--samples", type=int, default=16, help="the demo's Cycles samples")
p.add_argument("--repeats", type=int, default=1)
p.add_argument("--csv", default=os.path.join(ROOT, "bench", "results", "cycles_aerial.csv"))
p.add_argument("--cli", default=os.path.join(ROOT, "build", "welkin"))
args = p.parse_args(argv)

out = tempfile.mkdtemp(prefix="welkin_cycles_aerial_")
atexit.register(shutil.rmtree, out, ignore_errors=True)
rows = []


def row(name, seconds, note=""):
    rows.append((name, seconds, note))
    unit = "x" if note.startswith("ratio") else "s"
    print(f"cycles_aerial: {name} = {seconds:.4g} {unit} {note}", flush=True)


def timed(f):
    ts = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts)


# 1. The demo, rendered once with the add-on's aerial perspective.
t = time.perf_counter()
sys.argv = [sys.argv[0], "--", "--out", out, "--size", str(args.size), "--samples", str(args.samples)]
runpy.run_path(os.path.join(ROOT, "blend", "make_aerial_demo.py"), run_name="__main__")
t_demo = time.perf_counter() - t  # scene building + update_sky + render + aerial handler
scene = bpy.context.scene
W, H = scene.render.resolution_x, scene.render.resolution_y
size = f"{W}x{H}"
from welkin import native, scene_export  # noqa: E402  (the add-on's package)

welkin = native.module()  # the built module

base = scene_export.file_base(bpy.path.abspath(scene.render.filepath))
scene_json = scene_export.frame_path(base, "scene", 1)
render_exr = scene_export.frame_path(base, "render", 1)
assert os.path.exists(scene_json) and os.path.exists(render_exr), scene.welkin_aerial.status
row("demo_script_total", t_demo, f"{size}, {args.samples} spp: build, world texture, render, aerial handler")


def render_once():
    bpy.ops.render.render(write_still=False)


scene.welkin_aerial.enabled = False
t_cycles = timed(render_once)
row("cycles_frame", t_cycles, f"{args.samples} spp, aerial off")

# 2. the aerial passes of the same frame.
passes = os.path.join(out, "passes.exr")
for method in ("froxel", "raymarch"):
    cmd = [
        args.cli,
        "aerial",
        "--scene",
        scene_json,
        "--depth",
        render_exr,
        "--depth-channel",
        "Depth.V",
        "--method",
        method,
        "-o",
        passes,
        "--overwrite",
    ]
    t = timed(lambda: subprocess.run(cmd, check=True, capture_output=True))
    row(f"cli_aerial_{method}", t, "whole CLI call: LUTs, EXR read, passes, EXR write")
desc = welkin.SceneDescription.from_json(scene_json)
pixels, names = welkin.read_exr(render_exr)
depth = np.ascontiguousarray(pixels[..., names.index("Depth.V")])
for method in ("froxel", "raymarch"):
    t = timed(lambda: welkin.aerial_perspective(desc, depth, method))
    row(f"module_aerial_{method}", t, "welkin.aerial_perspective: LUTs, volume, application")
t_froxel = [r[1] for r in rows if r[0] == "module_aerial_froxel"][0]
row("cycles_over_aerial_froxel", t_cycles / t_froxel, "ratio (x), Cycles frame / module froxel passes")

# 3. the plate against Cycles on the same world.
t = timed(
    lambda: subprocess.run(
        [args.cli, "plate", "--scene", scene_json, "-o", os.path.join(out, "plate.exr"), "--overwrite"],
        check=True,
        capture_output=True,
    )
)
row("cli_plate", t, "welkin plate: LUTs, plate, EXR write")
scene.render.engine = "WELKIN"
t_engine = timed(render_once)
row("engine_plate", t_engine, "the WELKIN render engine's render call")
scene.render.engine = "CYCLES"
for obj in scene.objects:
    if obj.type == "MESH":
        obj.hide_render = True
for spp in (1, args.samples):
    scene.cycles.samples = spp
    t = timed(render_once)
    row(f"cycles_world_{spp}spp", t, "Cycles, world texture only (meshes hidden)")
    row(f"cycles_world_{spp}spp_over_engine", t / t_engine, "ratio (x)")

os.makedirs(os.path.dirname(os.path.abspath(args.csv)), exist_ok=True)
with open(args.csv, "w") as f:
    f.write("name,value,note\n")
    for r in rows:
        f.write(f'{r[0]},{r[1]:.5g},"{r[2]} ({size}, load {os.getloadavg()[0]:.1f})"\n')
print(f"cycles_aerial: wrote {args.csv}")
