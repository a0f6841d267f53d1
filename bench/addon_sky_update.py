# SPDX-License-Identifier: Apache-2.0
"""Benchmark (not a test): from rotating the sun lamp to the new world image, 2048 x 1024,
beside the time the same Blender spends preparing its own sky for a render, in one run.

    blender -b --factory-startup --python-use-system-env --python bench/addon_sky_update.py \
        [-- --repeats 7 --width 2048 [--clouds [--cloud-type altocumulus] [--march-afresh]]
            [--sky auto] [--docs]]

or, for PyPI's bpy of another Blender (the add-on installed from its Extension; scripts/
test_blender.sh builds it, WELKIN_EXTENSION_ZIP names it):

    WELKIN_EXTENSION_ZIP=build/blender_dist/welkin-0.1.0-linux_x64.zip \
      build/venv-bpy-5.3/bin/python tests/blender/bpy_blender.py -b --factory-startup \
      --python bench/addon_sky_update.py -- --repeats 5 --docs

--sky picks Blender's sky model: `auto` (the default) is that Blender's own best, its
Multiple Scattering sky from 5.0 on, Nishita's (single scattering) before. --docs puts the
run's row into docs/validation.md's table between its "addon-sky-update" markers (one row
per Blender version, replaced when that version runs again).

--clouds adds one cloud layer at the panel's defaults to the world first: the update is then
the cloudy sky (the core's upsampled cloud pass, docs/validation.md "Speed of a cloudy sky")
and the lamp's cloud shadow. Each update after the first lights the clouds' view samples
the last one kept (welkin.scene_sky_image, keep_cloud_samples): --march-afresh times it
without them, every update marching the clouds again.

The add-on is installed from its package as in the tests (tests/blender/addon_testing.py; a
temporary scripts directory, the machine's Blender configuration untouched). Measured,
medians of --repeats, each with a new sun elevation:
  * welkin update: what the handlers' timer runs after a lamp rotation (update.update_sky
    without packing: request, module, pixels into the Blender image, nodes, lamp),
    and within it the module's share (sky image + sun radiometry and disc model);
  * render preparation: a Cycles render of 8 x 4 pixels, 1 sample, through a panoramic
    camera, with (a) a constant-colour world, (b) Blender's sky after a change of its sun
    elevation (Cycles recomputes its sky texture), (c) the Welkin world after an update
    (Cycles loads the 2048 x 1024 float image); the preparation cost is (b) - (a) and
    (c) - (a).
"""

import argparse
import functools
import math
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402

argv = T.script_argv()
parser = argparse.ArgumentParser()
parser.add_argument("--repeats", type=int, default=7)
parser.add_argument("--width", type=int, default=2048)
parser.add_argument("--clouds", action="store_true", help="one cloud layer at the panel's defaults")
parser.add_argument(
    "--cloud-type",
    help="with --clouds: the layer's type (its preset, as the panel's Type sets it); default cumulus",
)
parser.add_argument(
    "--sky",
    default="auto",
    help="Blender's sky model (ShaderNodeTexSky.sky_type)"
    "; auto: MULTIPLE_SCATTERING where it exists (5.0+), else NISHITA",
)
parser.add_argument(
    "--march-afresh",
    action="store_true",
    help="each update marches the clouds again (welkin.scene_sky_image's keep_cloud_samples=False):"
    " the update without the samples kept from the last one",
)
parser.add_argument("--docs", action="store_true", help="put the row into docs/validation.md")
args = parser.parse_args(argv)

addon, welkin = T.install_addon()
if args.march_afresh:
    welkin.scene_sky_image = functools.partial(welkin.scene_sky_image, keep_cloud_samples=False)
from welkin.blender import compat  # noqa: E402
from welkin.blender.sky import update  # noqa: E402

sky_types = [i.identifier for i in bpy.types.ShaderNodeTexSky.bl_rna.properties["sky_type"].enum_items]
sky_type = (
    args.sky if args.sky != "auto" else next(t for t in ("MULTIPLE_SCATTERING", "NISHITA") if t in sky_types)
)
if sky_type not in sky_types:
    raise SystemExit(f"addon_sky_update: --sky {sky_type!r} is not one of this Blender's {sky_types}")
for flag, given in (("--cloud-type", args.cloud_type), ("--march-afresh", args.march_afresh)):
    if given and not args.clouds:
        raise SystemExit(f"addon_sky_update: {flag} needs --clouds")
if args.cloud_type and args.cloud_type not in welkin.CLOUD_TYPES:
    raise SystemExit(
        f"addon_sky_update: --cloud-type {args.cloud_type!r} is not one of {', '.join(welkin.CLOUD_TYPES)}"
    )
sky_name = {
    "MULTIPLE_SCATTERING": "Multiple Scattering",
    "NISHITA": "Nishita",
    "SINGLE_SCATTERING": "Single Scattering (Nishita)",
}.get(sky_type, sky_type)

scene, sun = T.new_scene(30.0, 45.0, resolution=str(args.width))
T.panoramic_camera(scene, 8, 4, samples=1)
if args.clouds:
    layer = scene.world.welkin_clouds.layers.add()
    layer.name = "Bench Layer"
    if args.cloud_type:
        layer.cloud_type = args.cloud_type
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
compat.world_node_tree(const_world)
nishita_world = bpy.data.worlds.new(sky_name)
sky_tree = compat.world_node_tree(nishita_world)
sky_node = sky_tree.nodes.new("ShaderNodeTexSky")
sky_node.sky_type = sky_type
background = next(n for n in sky_tree.nodes if n.bl_idname == "ShaderNodeBackground")
sky_tree.links.new(sky_node.outputs["Color"], background.inputs["Color"])

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
    (
        f"welkin: lamp rotation -> new world image {args.width}x{args.width // 2} ({method}"
        f"{(', one ' + (args.cloud_type or 'cumulus') + ' layer') if args.clouds else ''}"
        f"{', marched afresh' if args.march_afresh else ''})",
        med(total),
    ),
    ("  of which the module (sky + sun and disc model)", med(module_share)),
    ("  of which Blender (pixels into the image, nodes, lamp)", med(total) - med(module_share)),
    ("Cycles 8x4 render, constant world (baseline)", c),
    (f"Cycles: Blender's {sky_name} sky preparation, render - baseline", med(nishita) - c),
    (
        f"Cycles: Welkin world preparation (image {args.width}x{args.width // 2}), render - baseline",
        med(welkin_render) - c,
    ),
]
print(
    f"\nbench/addon_sky_update.py: medians of {args.repeats}, Blender {bpy.app.version_string}, "
    f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}"
)
for label, seconds in rows:
    print(f"| {label} | {seconds * 1000:.0f} ms |")
ratio = med(total) / max(med(nishita) - c, 1e-9)
print(f"| ratio: welkin update / {sky_name} preparation | {ratio:.2f} |")

if args.docs:
    BEGIN, END = "<!-- addon-sky-update:begin -->", "<!-- addon-sky-update:end -->"
    version = ".".join(map(str, bpy.app.version))
    row = (
        f"| {version} | {sys.version_info.major}.{sys.version_info.minor} | "
        f"{med(total) * 1000:.0f} ms ({med(module_share) * 1000:.0f} ms module) | "
        f"{sky_name}: {(med(nishita) - c) * 1000:.0f} ms | {ratio:.2f} | "
        f"{args.repeats} | {os.getloadavg()[0]:.1f} |"
    )
    doc = os.path.join(ROOT, "docs", "validation.md")
    with open(doc) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        raise SystemExit(f"addon_sky_update: no {BEGIN} ... {END} markers in {doc}")
    head, rest = text.split(BEGIN, 1)
    table, tail = rest.split(END, 1)
    lines = [line for line in table.strip().splitlines() if line.startswith("|")][:2]
    rows_by_version = {
        line.split("|")[1].strip(): line for line in table.strip().splitlines()[2:] if line.startswith("|")
    }
    rows_by_version[version] = row
    ordered = sorted(rows_by_version, key=lambda v: tuple(int(x) for x in v.split(".")))
    body = "\n".join(lines + [rows_by_version[v] for v in ordered])
    with open(doc, "w") as f:
        f.write(f"{head}{BEGIN}\n{body}\n{END}{tail}")
    print(f"written: {doc}")
