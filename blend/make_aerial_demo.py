"""Makes the aerial-perspective demo scene and renders it headless:

    blender -b --factory-startup --python-use-system-env --python blend/make_aerial_demo.py \
        [-- --out out/aerial_demo --size 480 --samples 16 --sheet docs/aerial_demo.png]

A ground plane 200 km across and pairs of blocks from 300 m out to 40 km, the camera 30 m up
looking along +X, the sun 8 degrees up to the camera's left, `hazy` air, the Welkin sky in
the world. With Scene.welkin_aerial enabled the render leaves OUT/frame_welkin_*_0001.*
(scene JSON, passes, composite: README "Aerial perspective in Blender"). --sheet writes the
render before (the render layer's Image) and after (Image x T + Inscatter) side by side as
one PNG (exposure 2^-3.5, x / (1 + x), sRGB).
"""
import argparse
import math
import os
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser()
parser.add_argument("--out", default=os.path.join(ROOT, "out", "aerial_demo"))
parser.add_argument("--size", type=int, default=480, help="image width, pixels")
parser.add_argument("--samples", type=int, default=16)
parser.add_argument("--sheet", help="write the before / after pair as one PNG")
args = parser.parse_args(argv)
os.makedirs(args.out, exist_ok=True)

import addon_utils  # noqa: E402

if not addon_utils.check("welkin")[1]:
    sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
    import addon_testing  # installs from the zip into a temporary scripts directory
    addon_testing.install_addon()
from mathutils import Vector  # noqa: E402

for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
scene = bpy.context.scene


def material(name, rgb):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    m.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*rgb, 1.0)
    return m


bpy.ops.mesh.primitive_plane_add(size=200000.0)
bpy.context.active_object.data.materials.append(material("Ground", (0.15, 0.16, 0.12)))
block = material("Block", (0.5, 0.5, 0.48))
for k, d in enumerate((300.0, 700.0, 1500.0, 3000.0, 6000.0, 12000.0, 24000.0, 40000.0)):
    for side in (-1.0, 1.0):  # a pair at each distance, nearer pairs further out
        s = 0.03 * d
        y = side * math.tan(math.radians(4.0 + 3.0 * (7 - k))) * d
        bpy.ops.mesh.primitive_cube_add(size=s, location=(d, y, 0.5 * s))
        bpy.context.active_object.data.materials.append(block)

cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(cam)
cam.location = (0.0, 0.0, 30.0)
cam.rotation_euler = (math.radians(88.5), 0.0, math.radians(-90.0))  # towards +X
cam.data.lens = 30.0
cam.data.clip_end = 1e6
scene.camera = cam
sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
scene.collection.objects.link(sun)
sun.rotation_mode = 'QUATERNION'
e, a = math.radians(8.0), math.radians(60.0)
sun.rotation_quaternion = Vector((0, 0, 1)).rotation_difference(
    Vector((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))))

settings = scene.world.welkin
settings.preset = "hazy"
settings.resolution = '1024'
bpy.ops.welkin.update_sky()

scene.render.engine = 'CYCLES'
scene.cycles.samples = args.samples
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = args.size, args.size * 9 // 16
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = 'OPEN_EXR'
scene.render.filepath = os.path.join(args.out, "frame_")
scene.frame_set(1)
scene.welkin_aerial.enabled = True
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(args.out, "welkin_aerial_demo.blend"))
bpy.ops.render.render(write_still=True)
print(f"make_aerial_demo: {scene.welkin_aerial.status}")

if args.sheet:
    import numpy as np
    from welkin import native, scene_export
    module = native.module()
    base = scene_export.file_base(bpy.path.abspath(scene.render.filepath))
    pixels, names = module.read_exr(scene_export.frame_path(base, "render", 1))
    before = np.stack([pixels[..., names.index(f"Image.{c}")] for c in "RGB"], axis=-1)
    pixels, names = module.read_exr(scene_export.frame_path(base, "composite", 1))
    after = np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)

    def display(x):
        x = np.maximum(x * 2.0 ** -3.5, 0.0)
        x = x / (1.0 + x)
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)

    gap = np.ones((before.shape[0], 4, 3), np.float32)
    sheet = np.concatenate([display(before), gap, display(after)], axis=1)[::-1]  # bottom first
    rgba = np.concatenate([sheet, np.ones(sheet.shape[:2] + (1,), np.float32)], axis=-1)
    out = bpy.data.images.new("sheet", rgba.shape[1], rgba.shape[0], alpha=True)
    out.pixels.foreach_set(np.ascontiguousarray(rgba, dtype=np.float32).ravel())
    out.filepath_raw = os.path.abspath(args.sheet)
    out.file_format = 'PNG'
    out.save()
    print(f"make_aerial_demo: before / after {args.sheet}")
