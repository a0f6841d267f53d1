"""Makes the demo scene and renders a short time-of-day sequence, headless:

    blender -b --factory-startup --python-use-system-env --python blend/make_demo.py \
        [-- --frames 6 --out out/demo --size 480 --samples 16 --no-render --sheet PNG]

A ground plane, a few objects, a camera looking along +X, and one sun lamp
animated from just below the horizon (frame 1) to 60 degrees up (last frame) while it
swings round behind the camera's left (azimuth 100 to 160 degrees). The Welkin add-on (installed from its zip into a temporary scripts
directory when it is not enabled already: `bash scripts/build_addon.sh` first) makes the
sky and syncs the lamp; the saved file `OUT/welkin_demo.blend` carries the packed sky,
and re-renders headless on any machine with the add-on installed:

    blender -b OUT/welkin_demo.blend --addons welkin -a

--sheet writes the frames side by side (two rows) as one PNG, e.g. docs/addon_demo.png.
Frames go to OUT/frame_####.png (Filmic, exposure -5 for the physical W m^-2 sr^-1
radiance scale, as with Blender's Nishita sky).
"""
import argparse
import math
import os
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser()
parser.add_argument("--frames", type=int, default=6)
parser.add_argument("--out", default=os.path.join(ROOT, "out", "demo"))
parser.add_argument("--size", type=int, default=480, help="image width, pixels")
parser.add_argument("--samples", type=int, default=16)
parser.add_argument("--no-render", action="store_true")
parser.add_argument("--sheet", help="also write the frames as one contact-sheet PNG")
args = parser.parse_args(argv)
os.makedirs(args.out, exist_ok=True)

import addon_utils  # noqa: E402

if not addon_utils.check("welkin")[1]:
    sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
    import addon_testing  # installs from the zip into a temporary scripts directory
    addon_testing.install_addon()

for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
scene = bpy.context.scene


def add(obj):
    scene.collection.objects.link(obj)
    return obj


def material(name, rgb, roughness=0.6):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    return m


bpy.ops.mesh.primitive_plane_add(size=400.0)
ground = bpy.context.active_object
ground.data.materials.append(material("Ground", (0.18, 0.17, 0.15), 0.9))
for i, (x, y, r, rgb) in enumerate(((6, -2, 1.0, (0.8, 0.8, 0.8)), (9, 2, 1.5, (0.7, 0.3, 0.2)),
                                    (13, -4, 2.0, (0.2, 0.4, 0.7)))):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=(x, y, r), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(material(f"Ball {i}", rgb, 0.3))
bpy.ops.mesh.primitive_cube_add(size=3.0, location=(11, 6, 1.5))
bpy.context.active_object.data.materials.append(material("Block", (0.6, 0.6, 0.55)))

cam = add(bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera")))
cam.location = (-4.0, 0.0, 1.7)
cam.rotation_euler = (math.radians(84.0), 0.0, math.radians(-90.0))  # towards +X
cam.data.lens = 24.0
scene.camera = cam

sun = add(bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN')))
sun.rotation_mode = 'QUATERNION'
from mathutils import Vector  # noqa: E402

scene.frame_start, scene.frame_end = 1, args.frames
for f in range(1, args.frames + 1):
    t = (f - 1) / max(1, args.frames - 1)
    e, a = math.radians(-1.0 + 61.0 * t), math.radians(100.0 + 60.0 * t)
    d = Vector((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)))
    sun.rotation_quaternion = Vector((0, 0, 1)).rotation_difference(d)
    sun.keyframe_insert("rotation_quaternion", frame=f)

settings = scene.world.welkin
settings.resolution = '1024'
scene.frame_set(1)
bpy.ops.welkin.update_sky()

scene.render.engine = 'CYCLES'
scene.cycles.samples = args.samples
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = args.size, args.size * 9 // 16
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = 'PNG'
scene.view_settings.view_transform = 'Filmic'
scene.view_settings.exposure = -4.0
scene.render.filepath = os.path.join(args.out, "frame_####")
blend = os.path.join(args.out, "welkin_demo.blend")
bpy.ops.wm.save_as_mainfile(filepath=blend)
print(f"make_demo: saved {blend}")
if not args.no_render:
    bpy.ops.render.render(animation=True)
    print(f"make_demo: rendered frames 1-{args.frames} to {args.out}")
    if args.sheet:
        import numpy as np
        frames = []
        for f in range(1, args.frames + 1):
            image = bpy.data.images.load(os.path.join(args.out, f"frame_{f:04d}.png"))
            w, h = image.size
            px = np.empty(w * h * 4, dtype=np.float32)
            image.pixels.foreach_get(px)
            frames.append(px.reshape(h, w, 4))  # bottom row first, as Blender keeps them
            bpy.data.images.remove(image)
        cols = (len(frames) + 1) // 2
        frames += [np.zeros_like(frames[0])] * (2 * cols - len(frames))
        top = np.concatenate(frames[:cols], axis=1)
        bottom = np.concatenate(frames[cols:], axis=1)
        sheet = np.concatenate([bottom, top], axis=0)  # bottom-first: first row on top
        out = bpy.data.images.new("sheet", sheet.shape[1], sheet.shape[0], alpha=True)
        out.pixels.foreach_set(sheet.ravel())
        out.filepath_raw = os.path.abspath(args.sheet)
        out.file_format = 'PNG'
        out.save()
        print(f"make_demo: contact sheet {args.sheet}")
