# SPDX-License-Identifier: Apache-2.0
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
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import demo_scene as ds  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("--frames", type=int, default=6)
parser.add_argument("--out", default=os.path.join(ds.ROOT, "out", "demo"))
parser.add_argument("--size", type=int, default=480, help="image width, pixels")
parser.add_argument("--samples", type=int, default=16)
parser.add_argument("--no-render", action="store_true")
parser.add_argument("--sheet", help="also write the frames as one contact-sheet PNG")
args = ds.script_args(parser)
os.makedirs(args.out, exist_ok=True)
ds.enable_welkin()
scene = ds.empty_scene()
material = ds.material


bpy.ops.mesh.primitive_plane_add(size=400.0)
ground = bpy.context.active_object
ground.data.materials.append(material("Ground", (0.18, 0.17, 0.15), 0.9))
for i, (x, y, r, rgb) in enumerate(
    ((6, -2, 1.0, (0.8, 0.8, 0.8)), (9, 2, 1.5, (0.7, 0.3, 0.2)), (13, -4, 2.0, (0.2, 0.4, 0.7)))
):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=(x, y, r), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(material(f"Ball {i}", rgb, 0.3))
bpy.ops.mesh.primitive_cube_add(size=3.0, location=(11, 6, 1.5))
bpy.context.active_object.data.materials.append(material("Block", (0.6, 0.6, 0.55), 0.6))

ds.add_camera(scene, (-4.0, 0.0, 1.7), 84.0, 24.0)
sun = ds.add_sun(scene)
scene.frame_start, scene.frame_end = 1, args.frames
for f in range(1, args.frames + 1):
    t = (f - 1) / max(1, args.frames - 1)
    ds.aim_sun(sun, -1.0 + 61.0 * t, 100.0 + 60.0 * t)
    sun.keyframe_insert("rotation_quaternion", frame=f)

settings = scene.world.welkin
settings.resolution = "1024"
scene.frame_set(1)
bpy.ops.welkin.update_sky()

ds.cycles(scene, args.samples, args.size)
scene.render.image_settings.file_format = "PNG"
scene.view_settings.view_transform = "Filmic"
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
        ds.save_png(sheet, args.sheet)
        print(f"make_demo: contact sheet {args.sheet}")
