# SPDX-License-Identifier: Apache-2.0
"""Benchmark (not a test): the render engine "WELKIN" rendering a frame with one cloud layer
of each type at its preset, as an artist's F12 or a farm's `blender -b file.blend -E WELKIN
-f 1` does, in real Blender. The add-on is installed from its package (tests/blender/
addon_testing.py); the scene is its own: the camera 20 m up looking 15 degrees above the
horizon (70 degree lens, as bench/clouds/plate_types.py), the sun lamp 35 degrees up. Each
type's .blend is rendered by a command-line Blender; the time is the whole process (start-
up, the add-on, the scene's sync, the plate in bands, the multilayer EXR), and the frame
is checked (finite, clouds in view).

    blender -b --factory-startup --python-use-system-env --python bench/clouds/engine_plate_types.py \
        -- [--width 1920 --types cumulus cirrus]

or through PyPI's bpy (WELKIN_EXTENSION_ZIP names the add-on's package):

    WELKIN_EXTENSION_ZIP=build/blender_dist/welkin-0.1.0-linux_x64.zip \
      build/venv-bpy-5.3/bin/python tests/blender/bpy_blender.py -b --factory-startup \
      --python bench/clouds/engine_plate_types.py -- --width 1920
"""

import argparse
import math
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "blender"))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

argv = t.script_argv()
ap = argparse.ArgumentParser()
ap.add_argument("--width", type=int, default=1920)
ap.add_argument("--types", nargs="*", default=None)
args = ap.parse_args(argv)

addon, native = t.install_addon()
from welkin.blender import compat  # noqa: E402

TARGET_S = 10.0  # the target for a 1920 x 1080 plate with one layer (the ratio column)


def blend_for(cloud_type):
    scene, _sun = t.new_scene(sun_elevation_deg=35.0, sun_azimuth_deg=30.0, camera_z=20.0)
    cam = scene.camera
    cam.rotation_euler = (math.radians(90.0 + 15.0), 0.0, math.radians(-90.0))  # along +X, 15 deg up
    cam.data.sensor_width = 36.0
    cam.data.angle = math.radians(70.0)
    world = scene.world
    world.welkin_clouds.layers.clear()
    ct.add_layer(world, cloud_type=cloud_type)
    scene.render.engine = "WELKIN"
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.width * 9 // 16
    scene.render.resolution_percentage = 100
    compat.set_file_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER")
    scene.render.image_settings.color_depth = "32"
    path = t.TMP / f"{cloud_type}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def render(blend, stem):
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(t.scripts_dir()))
    env.pop("PYTHONPATH", None)
    cmd = [*t.blender_command(), "-b", str(blend), "--addons", "welkin", "-E", "WELKIN"]
    cmd += ["-o", str(stem) + "_####", "-F", "OPEN_EXR_MULTILAYER", "-f", "1"]
    t0 = time.perf_counter()
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    wall = time.perf_counter() - t0
    if run.returncode != 0:
        raise SystemExit(f"engine_plate_types: {blend.name}: exit {run.returncode}\n{run.stderr[-2000:]}")
    return wall


types = args.types or list(native.CLOUD_TYPES)
h = args.width * 9 // 16
print(f"| type | engine, {args.width} x {h} (whole process) | / {TARGET_S:.0f} s | cloud cover |")
print("|---|---|---|---|")
for cloud_type in types:
    stem = t.TMP / cloud_type
    wall = render(blend_for(cloud_type), stem)
    pixels, names = native.read_exr(str(stem) + "_0001.exr")
    alpha = pixels[..., names.index("ViewLayer.Welkin.Clouds.A")]
    rgb = np.stack([pixels[..., names.index(f"ViewLayer.Combined.{c}")] for c in "RGB"], -1)
    if not (np.isfinite(rgb).all() and (rgb >= 0).all() and (alpha > 0.05).mean() > 0.02):
        raise SystemExit(f"engine_plate_types: {cloud_type}: a bad frame (non-finite, negative or no cloud)")
    print(
        f"| {cloud_type} | {wall:.2f} s | {wall / TARGET_S:.2f}x | {(alpha > 0.05).mean():.2f} |", flush=True
    )
print(f"Blender {bpy.app.version_string}, {len(os.sched_getaffinity(0))} CPUs")
