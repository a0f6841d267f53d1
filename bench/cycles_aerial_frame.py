# SPDX-License-Identifier: Apache-2.0
"""What aerial perspective in the frame costs a Cycles render of the aerial demo: the same
frame rendered with Scene.welkin_aerial off and on, alternately, in one Blender process.

    bash scripts/build_addon.sh && BLENDER_USER_SCRIPTS=$(mktemp -d) blender -b \
        --factory-startup --python-use-system-env --python bench/cycles_aerial_frame.py -- \
        [--size 480] [--samples 16] [--repeats 3] [--csv bench/results/cycles_aerial_frame.csv]

It benches the add-on zip in dist/ (blend/demo_scene.py installs it into the empty user
scripts folder, and refuses a zip older than the add-on's sources or the compiled module in
build/: a stale zip would time the previous code).

blend/make_aerial_demo.py builds the demo (ground and blocks to 40 km, `hazy`, the Welkin
world) at --size; then each repeat renders frame 1 (bpy.ops.render.render, the render call
with scene sync) without and with aerial perspective. "On" includes everything the
feature adds to a frame: the table's bake (forced every time: the add-on's cache of it is
cleared before each render), the material node group's evaluation at the camera hits, the
AOVs and the compositor group; "on, cached" renders again with the table already baked, and
the bake is also timed alone. The figure is the median over the repeats of each repeat's
ratio to its own "off" render (target: <= 1.10; the order of the three alternates from one
repeat to the next), of the wall time and of the process's CPU time (all threads), with a
bootstrap 90 % interval for the wall-time figure. A 2-second render on this shared machine
varies by about 10 % (standard deviation) from one render to the next, with no drift that
pairing would cancel, so the median of 41 repeats is known to some +-4 %, and two runs of
121 repeats still differ by about a per cent (the machine's state changes between them):
pass --repeats 121 or more, and pool runs (bench/cycles_log_split.py takes several
logs), to settle a figure near the target.

--markers prints a line after each render; run with Blender's --debug-cycles and the output
kept in a file, bench/cycles_log_split.py then splits each render's time into Cycles' path
tracing, the rest of Cycles' render (scene and image sync) and what lies outside Cycles (the
handlers and the bake, the compositor, saving), each as the median difference to the same
repeat's "off" render.

--group-only replaces the demo's shading by emission of each material's base colour and
turns bounces off, so that what is left of a render is its camera rays and the material
group: the group's own cost, reported per camera sample (pixels x samples) in ns, as the
CPU time the cached state adds.
"""

import argparse
import atexit
import os
import runpy
import shutil
import statistics
import sys
import tempfile
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
p = argparse.ArgumentParser()
p.add_argument("--size", type=int, default=480)
p.add_argument("--samples", type=int, default=16)
p.add_argument("--repeats", type=int, default=3)
p.add_argument("--csv")
p.add_argument("--group-only", action="store_true")
p.add_argument(
    "--markers",
    action="store_true",
    help="print a line per render (repeat, state, wall and CPU time) for "
    "bench/cycles_log_split.py to pair with Cycles' own timings",
)
args = p.parse_args(argv)

out = tempfile.mkdtemp(prefix="welkin_bench_aerial_frame_")
atexit.register(shutil.rmtree, out, ignore_errors=True)
sys.argv = [sys.argv[0], "--", "--out", out, "--size", str(args.size), "--samples", str(args.samples)]
runpy.run_path(os.path.join(ROOT, "blend", "make_aerial_demo.py"), run_name="__main__")
scene = bpy.context.scene
aerial = sys.modules[next(m for m in sys.modules if m.endswith("welkin.blender.aerial"))]
scene.render.filepath = os.path.join(out, "bench.exr")
scene.welkin_aerial.side_files = False  # the frame alone: no Z pass, no pass files
if args.group_only:
    scene.cycles.max_bounces = 0
    for material in bpy.data.materials:
        tree = material.node_tree
        if tree is None or "Principled BSDF" not in tree.nodes:
            continue
        emission = tree.nodes.new("ShaderNodeEmission")
        emission.inputs["Color"].default_value = (
            tree.nodes["Principled BSDF"].inputs["Base Color"].default_value
        )
        tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])

times = {"off": [], "on": [], "on_cached": [], "bake": []}
cpu = {"off": [], "on": [], "on_cached": []}  # the process's CPU time, all threads: steadier
for repeat in range(args.repeats):
    # Alternate the order (off, on, cached / cached, on, off) so that a drift of the
    # machine's speed over a repeat does not favour one state.
    order = ("off", "on", "on_cached") if repeat % 2 == 0 else ("on_cached", "on", "off")
    for state in order:
        scene.welkin_aerial.enabled = state != "off"
        if state == "on":
            aerial._baked.clear()
        elif state == "on_cached" and not aerial._baked:
            aerial.bake(scene)
        t0, c0 = time.perf_counter(), time.process_time()
        bpy.ops.render.render(write_still=True)
        times[state].append(time.perf_counter() - t0)
        cpu[state].append(time.process_time() - c0)
        if args.markers:
            print(
                f"cycles_aerial_frame: render {repeat} {state} wall {times[state][-1]:.4f} "
                f"cpu {cpu[state][-1]:.4f}",
                flush=True,
            )
    aerial._baked.clear()
    t0 = time.perf_counter()
    aerial.bake(scene)
    times["bake"].append(time.perf_counter() - t0)


def ratio(series, state):
    """The median over repeats of each repeat's ratio to its own "off" render."""
    return statistics.median(a / b for a, b in zip(series[state], series["off"]))


def ratio_interval(series, state, level=0.90, resamples=4000):
    """A bootstrap interval of ratio(series, state): the central `level` of the medians of
    `resamples` resamplings of the repeats (with replacement; seeded, so a log reads the
    same twice); it sees the noise within a run, not what changes between runs."""
    r = np.array(series[state]) / np.array(series["off"])
    medians = np.median(np.random.default_rng(0).choice(r, (resamples, r.size)), axis=1)
    return tuple(np.quantile(medians, [(1.0 - level) / 2.0, (1.0 + level) / 2.0]))


m = {k: statistics.median(v) for k, v in times.items()}
low = {k: min(v) for k, v in cpu.items()}  # noise only adds: the least CPU time is the steadiest
c = {k: statistics.median(v) for k, v in cpu.items()}
r = {k: ratio(times, k) for k in ("on", "on_cached")}
ci = {k: ratio_interval(times, k) for k in ("on", "on_cached")}
rc = {k: ratio(cpu, k) for k in ("on", "on_cached")}
print(
    f"cycles_aerial_frame: {args.size} px wide, {args.samples} samples, {args.repeats} repeats "
    f"(medians; ratios: the median of each repeat's ratio): off {m['off']:.2f} s, on "
    f"{m['on']:.2f} s (ratio {r['on']:.3f}, 90 % interval {ci['on'][0]:.3f}-{ci['on'][1]:.3f}, "
    f"target <= 1.10), on with the table already baked {m['on_cached']:.2f} s (ratio "
    f"{r['on_cached']:.3f}, {ci['on_cached'][0]:.3f}-{ci['on_cached'][1]:.3f}); the bake alone "
    f"{m['bake']:.3f} s; "
    f"CPU time: off {c['off']:.2f} s, on {c['on']:.2f} s (ratio {rc['on']:.3f}), cached "
    f"{c['on_cached']:.2f} s (ratio {rc['on_cached']:.3f}); least CPU time: off {low['off']:.2f} s, on "
    f"{low['on']:.2f} s (ratio {low['on'] / low['off']:.3f}), cached {low['on_cached']:.2f} s (ratio "
    f"{low['on_cached'] / low['off']:.3f})"
)
if args.group_only:
    samples = scene.render.resolution_x * scene.render.resolution_y * scene.cycles.samples
    per_sample = (c["on_cached"] - c["off"]) / samples * 1e9
    print(
        f"cycles_aerial_frame: --group-only: the group adds {per_sample:.0f} ns of CPU time per "
        f"camera sample ({samples} samples)"
    )
if args.csv:
    with open(args.csv, "w") as f:
        f.write(
            "size,samples,repeats,off_s,on_s,on_cached_s,bake_s,ratio,ratio_lo90,ratio_hi90,"
            "off_cpu_s,on_cpu_s,on_cached_cpu_s,cpu_ratio,least_cpu_ratio\n"
        )
        f.write(
            f"{args.size},{args.samples},{args.repeats},{m['off']:.3f},{m['on']:.3f},"
            f"{m['on_cached']:.3f},{m['bake']:.3f},{r['on']:.4f},{ci['on'][0]:.4f},"
            f"{ci['on'][1]:.4f},{c['off']:.3f},"
            f"{c['on']:.3f},{c['on_cached']:.3f},{rc['on']:.4f},{low['on'] / low['off']:.4f}\n"
        )
