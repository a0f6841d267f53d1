"""Benchmark (not a test): from rotating the sun lamp to the new world image, 2048 x 1024,
beside the time Blender spends preparing its own Nishita sky for a render, in one run.

    blender -b --factory-startup --python-use-system-env --python bench/addon_sky_update.py \
        [-- --repeats 7 --width 2048 [--clouds]]

--clouds adds one cloud layer at the panel's defaults to the world first: the update is then
the cloudy sky (the core's upsampled cloud pass, docs/validation.md "Speed of a cloudy sky")
and the lamp's cloud shadow.

The add-on is installed from its zip as in the tests (tests/blender/addon_testing.py; a
temporary scripts directory, the machine's Blender configuration untouched). Measured,
medians of --repeats, each with a new sun elevation:
  * welkin update: what the handlers' timer runs after a lamp rotation (update.update_sky
    without packing: request, module, pixels into the Blender image, nodes, lamp),
    and within it the module's share (sky image + sun radiometry and disc model);
  * render preparation: a Cycles render of 8 x 4 pixels, 1 sample, through a panoramic
    camera, with (a) a constant-colour world, (b) Blender's Nishita sky after a change of
    its sun elevation (Cycles recomputes its 512 x 128 Nishita texture), (c) the Welkin
    world after an update (Cycles loads the 2048 x 1024 float image); the
    preparation cost is (b) - (a) and (c) - (a).
"""
import argparse
import math
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser()
parser.add_argument("--repeats", type=int, default=7)
parser.add_argument("--width", type=int, default=2048)
parser.add_argument("--clouds", action="store_true", help="one cloud layer at the panel's defaults")
args = parser.parse_args(argv)

addon, welkin = T.install_addon()
from welkin.blender.sky import update  # noqa: E402

scene, sun = T.new_scene(30.0, 45.0, resolution=str(args.width))
T.panoramic_camera(scene, 8, 4, samples=1)
if args.clouds:
    layer = scene.world.welkin_clouds.layers.add()
    layer.name = "Bench Layer"
bpy.ops.welkin.update_sky()  # the first update creates images and nodes
elevations = [10.0 + 40.0 * k / max(1, args.repeats - 1) for k in range(args.repeats)]

total, module_share = [], []
for e in elevations:
    T.aim_sun(sun, e, 45.0)
    bpy.context.view_layer.update()
    t0 = time.perf_counter()
    outcome = update.update_sky(scene, None, pack=False)
    total.append(time.perf_counter() - t0)
    module_share.append(outcome.seconds)
method = outcome.method


def render_seconds():
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    return time.perf_counter() - t0


welkin_world = scene.world
const_world = bpy.data.worlds.new("Constant")
const_world.use_nodes = True
nishita_world = bpy.data.worlds.new("Nishita")
nishita_world.use_nodes = True
sky_node = nishita_world.node_tree.nodes.new('ShaderNodeTexSky')
sky_node.sky_type = 'NISHITA'
nishita_world.node_tree.links.new(sky_node.outputs['Color'],
                                  nishita_world.node_tree.nodes['Background'].inputs['Color'])

scene.world = const_world
render_seconds()  # warm-up: kernels, first session
constant, nishita, welkin_render = [], [], []
for e in elevations:
    scene.world = const_world
    constant.append(render_seconds())
    scene.world = nishita_world
    sky_node.sun_elevation = math.radians(e)
    nishita.append(render_seconds())
    scene.world = welkin_world
    T.aim_sun(sun, e + 0.5, 45.0)
    bpy.context.view_layer.update()
    update.update_sky(scene, None, pack=False)
    welkin_render.append(render_seconds())

med = statistics.median
c = med(constant)
rows = [
    (f"welkin: lamp rotation -> new world image {args.width}x{args.width // 2} ({method}"
     f"{', one cloud layer' if args.clouds else ''})",
     med(total)),
    ("  of which the module (sky + sun and disc model)", med(module_share)),
    ("  of which Blender (pixels into the image, nodes, lamp)", med(total) - med(module_share)),
    ("Cycles 8x4 render, constant world (baseline)", c),
    ("Cycles: Nishita sky preparation (512x128 texture), render - baseline", med(nishita) - c),
    (f"Cycles: Welkin world preparation (image {args.width}x{args.width // 2}), "
     f"render - baseline", med(welkin_render) - c),
]
print(f"\nbench/addon_sky_update.py: medians of {args.repeats}, Blender {bpy.app.version_string}, "
      f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
for label, seconds in rows:
    print(f"| {label} | {seconds * 1000:.0f} ms |")
print(f"| ratio: welkin update / Nishita preparation | "
      f"{med(total) / max(med(nishita) - c, 1e-9):.2f} |")
