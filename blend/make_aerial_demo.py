# SPDX-License-Identifier: Apache-2.0
"""Makes the aerial-perspective demo scene and renders it headless:

    blender -b --factory-startup --python-use-system-env --python blend/make_aerial_demo.py \
        [-- --out out/aerial_demo --size 480 --samples 16 --sheet docs/aerial_blender_demo.png]
        [-- --frames 4 --no-render]

A ground plane 200 km across and pairs of blocks from 300 m out to 40 km, the camera 30 m up
looking along +X, the sun 8 degrees up to the camera's left, `hazy` air, the Welkin sky in
the world. With Scene.welkin_aerial enabled the render leaves OUT/frame_welkin_*_0001.*
(scene JSON, passes, composite: docs/artists.md "Aerial perspective in Blender"). --sheet writes the
render before (the render layer's Image) and after (Image x T + Inscatter) side by side as
one PNG (exposure 2^-3.5, x / (1 + x), sRGB). --frames N makes a sequence, frames 1-N, the
sun rising one degree a frame (the farm tests render it, tests/farm/); --no-render saves
the .blend only.
"""

import argparse
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import demo_scene as ds  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("--out", default=os.path.join(ds.ROOT, "out", "aerial_demo"))
parser.add_argument("--size", type=int, default=480, help="image width, pixels")
parser.add_argument("--samples", type=int, default=16)
parser.add_argument("--sheet", help="write the before / after pair as one PNG")
parser.add_argument("--frames", type=int, default=1, help="frames 1-N, the sun rising 1 degree a frame")
parser.add_argument("--no-render", action="store_true", help="save the .blend, render nothing")
args = ds.script_args(parser)
os.makedirs(args.out, exist_ok=True)
addon_name = ds.enable_welkin()
scene = ds.empty_scene()
material = ds.material


bpy.ops.mesh.primitive_plane_add(size=200000.0)
bpy.context.active_object.data.materials.append(material("Ground", (0.15, 0.16, 0.12)))
block = material("Block", (0.5, 0.5, 0.48))
for k, d in enumerate((300.0, 700.0, 1500.0, 3000.0, 6000.0, 12000.0, 24000.0, 40000.0)):
    for side in (-1.0, 1.0):  # a pair at each distance, nearer pairs further out
        s = 0.03 * d
        y = side * math.tan(math.radians(4.0 + 3.0 * (7 - k))) * d
        bpy.ops.mesh.primitive_cube_add(size=s, location=(d, y, 0.5 * s))
        bpy.context.active_object.data.materials.append(block)

ds.add_camera(scene, (0.0, 0.0, 30.0), 88.5, 30.0, clip_end_m=1e6)
sun = ds.add_sun(scene)
ds.aim_sun(sun, 8.0, 60.0)
if args.frames > 1:
    scene.frame_start, scene.frame_end = 1, args.frames
    for frame in range(1, args.frames + 1):
        ds.aim_sun(sun, 8.0 + (frame - 1), 60.0)
        sun.keyframe_insert("rotation_quaternion", frame=frame)

settings = scene.world.welkin
settings.preset = "hazy"
settings.resolution = "1024"
bpy.ops.welkin.update_sky()

ds.cycles(scene, args.samples, args.size)
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.filepath = os.path.join(args.out, "frame_")
scene.frame_set(1)
# The frame itself is hazed; the pass files (the render's Image and Z pass, the passes, the
# hazed composite) are written too, for --sheet and for bench/cycles_aerial.py.
scene.welkin_aerial.side_files = True
scene.welkin_aerial.enabled = True
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(args.out, "welkin_aerial_demo.blend"))
if args.no_render:
    raise SystemExit(0)
bpy.ops.render.render(write_still=True)
print(f"make_aerial_demo: {scene.welkin_aerial.status}")

if args.sheet:
    import importlib

    import numpy as np

    native = importlib.import_module(f"{addon_name}.native")
    scene_export = importlib.import_module(f"{addon_name}.scene_export")
    module = native.module()
    base = scene_export.file_base(bpy.path.abspath(scene.render.filepath))
    pixels, names = module.read_exr(scene_export.frame_path(base, "render", 1))
    before = np.stack([pixels[..., names.index(f"Image.{c}")] for c in "RGB"], axis=-1)
    # The frame Blender wrote: hazed in the render itself (the Composite output).
    pixels, names = module.read_exr(bpy.path.abspath(scene.render.filepath) + scene.render.file_extension)
    after = np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)

    def display(x):
        x = np.maximum(x * 2.0**-3.5, 0.0)
        x = x / (1.0 + x)
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)

    gap = np.ones((before.shape[0], 4, 3), np.float32)
    sheet = np.concatenate([display(before), gap, display(after)], axis=1)[::-1]  # bottom first
    rgba = np.concatenate([sheet, np.ones(sheet.shape[:2] + (1,), np.float32)], axis=-1)
    ds.save_png(rgba, args.sheet)
    print(f"make_aerial_demo: before / after {args.sheet}")
