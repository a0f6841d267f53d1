# SPDX-License-Identifier: Apache-2.0
"""What the demo scenes (make_demo.py, make_aerial_demo.py) build alike, in Blender.

Imported by those scripts with blend/ on sys.path; nothing here runs on its own.
"""

import math
import os
import sys

import bpy
from mathutils import Vector

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def script_args(parser):
    """Parses the arguments after Blender's `--`."""
    return parser.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else [])


def enable_welkin():
    """Enables the Welkin add-on: the one the user installed when there is one (legacy
    add-on or Extension), else the zip that `bash scripts/build_addon.sh` built (dist/),
    installed into the user's add-ons as Preferences > Install would; a zip older than the
    add-on's sources or build/'s compiled module is refused (it holds the previous code)."""
    import glob

    import addon_utils

    names = [m.__name__ for m in addon_utils.modules() if m.__name__.split(".")[-1] == "welkin"]
    for name in names:
        if addon_utils.check(name)[1]:
            return name
    if names:
        bpy.ops.preferences.addon_enable(module=names[0])
        return names[0]
    zips = sorted(glob.glob(os.path.join(ROOT, "dist", "welkin-*.zip")))
    zips = [z for z in zips if not z.endswith("linux_x64.zip")]  # the Extension: 4.2+
    if not zips:
        raise SystemExit(
            "demo: the Welkin add-on is not installed and dist/ holds no "
            "welkin-<version>.zip; run bash scripts/build_addon.sh first"
        )
    sources = [
        f for f in glob.glob(os.path.join(ROOT, "addon", "**", "*"), recursive=True) if "__pycache__" not in f
    ]
    sources += glob.glob(os.path.join(ROOT, "build", "welkin.cpython*"))
    if os.path.getmtime(zips[-1]) < max(map(os.path.getmtime, sources), default=0.0):
        raise SystemExit(
            f"demo: {zips[-1]} is older than addon/ or build/'s compiled module; "
            "run bash scripts/build_addon.sh first"
        )
    bpy.ops.preferences.addon_install(filepath=zips[-1])
    bpy.ops.preferences.addon_enable(module="welkin")
    return "welkin"


def empty_scene():
    """The current scene with every object removed."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    return bpy.context.scene


def material(name, rgb, roughness=None):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    if roughness is not None:
        bsdf.inputs["Roughness"].default_value = roughness
    return m


def add_camera(scene, location, pitch_deg, lens_mm, clip_end_m=None):
    """The scene camera at `location`, looking along +X, `pitch_deg` from straight down
    (90: level)."""
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = location
    cam.rotation_euler = (math.radians(pitch_deg), 0.0, math.radians(-90.0))
    cam.data.lens = lens_mm
    if clip_end_m is not None:
        cam.data.clip_end = clip_end_m
    scene.camera = cam
    return cam


def add_sun(scene):
    """A sun lamp, rotated by quaternion (see aim_sun)."""
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    scene.collection.objects.link(sun)
    sun.rotation_mode = "QUATERNION"
    return sun


def aim_sun(sun, elevation_deg, azimuth_deg):
    """Points the lamp's +Z (towards the sun) at elevation / azimuth (counter-clockwise
    from +X)."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    d = Vector((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)))
    sun.rotation_quaternion = Vector((0, 0, 1)).rotation_difference(d)


def cycles(scene, samples, width):
    """Cycles at `samples` per pixel, no denoising, `width` x 9/16 pixels."""
    scene.render.engine = "CYCLES"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = width, width * 9 // 16
    scene.render.resolution_percentage = 100


def save_png(rgba, path):
    """An (h, w, 4) float array, bottom row first as Blender keeps images, to a PNG."""
    import numpy as np

    out = bpy.data.images.new("sheet", rgba.shape[1], rgba.shape[0], alpha=True)
    out.pixels.foreach_set(np.ascontiguousarray(rgba, dtype=np.float32).ravel())
    out.filepath_raw = os.path.abspath(path)
    out.file_format = "PNG"
    out.save()
    bpy.data.images.remove(out)
