# SPDX-License-Identifier: Apache-2.0
"""`blender -b file.blend -E WELKIN -a` over 3 frames writes 3 frames, each finite and its
own: the sun lamp is animated (elevation 10, 20, 30 degrees), so every frame's sky
differs; each frame's Combined equals welkin.camera_plate (the core call `welkin plate
--scene` makes) on that frame's scene JSON within 1 % (relative to max(value, 1e-3 x the image mean); the same core call)."""

import math
import os
import pathlib
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

addon, native = t.install_addon()
from welkin.blender import compat  # noqa: E402
from welkin.blender.engine import render_engine  # noqa: E402

check = t.check
scene, sun = t.new_scene(sun_elevation_deg=10.0, sun_azimuth_deg=0.0, camera_z=30.0)
cam = scene.camera
cam.rotation_euler = (math.radians(92.0), 0.0, math.radians(-90.0))  # along +X, 2 deg up
for frame, elevation in ((1, 10.0), (2, 20.0), (3, 30.0)):
    t.aim_sun(sun, elevation, 0.0)
    sun.keyframe_insert("rotation_quaternion", frame=frame)
scene.render.engine = "WELKIN"
scene.render.resolution_x, scene.render.resolution_y = 48, 32
scene.render.resolution_percentage = 100
compat.set_file_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER")
scene.render.image_settings.color_depth = "32"
scene.world.welkin.method = "lut"
scene.frame_start, scene.frame_end = 1, 3
blend = t.TMP / "anim.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))

env = dict(os.environ, BLENDER_USER_SCRIPTS=str(t.scripts_dir()))
env.pop("PYTHONPATH", None)
run = subprocess.run(
    [
        *t.blender_command(),
        "-b",
        str(blend),
        "--addons",
        "welkin",
        "-E",
        "WELKIN",
        "-o",
        str(t.TMP / "anim_####"),
        "-F",
        "OPEN_EXR_MULTILAYER",
        "-a",
    ],
    env=env,
    capture_output=True,
    text=True,
    timeout=600,
)
print(run.stdout[-1000:], run.stderr[-500:])
check(run.returncode == 0, f"blender -a exited {run.returncode}")

frames = []
for f in (1, 2, 3):
    pixels, names = native.read_exr(str(t.TMP / f"anim_{f:04d}.exr"))
    img = np.stack([pixels[..., names.index(f"ViewLayer.Combined.{c}")] for c in "RGB"], -1)
    check(np.isfinite(img).all() and img.max() > 0, f"frame {f}: not finite or black")
    frames.append(img)
    scene.frame_set(f)
    text = render_engine.scene_description_json(scene, bpy.context.evaluated_depsgraph_get(), native)
    ref = native.camera_plate(text)["combined"]
    err = np.abs(img - ref) / np.maximum(np.abs(ref), 1e-3 * float(np.abs(ref).mean()))
    check(err.max() < 0.01, f"frame {f}: Combined differs from the plate by {err.max():.3g}")
for i, j in ((0, 1), (1, 2), (0, 2)):
    d = float(np.abs(frames[i] - frames[j]).max() / np.abs(frames[j]).max())
    check(d > 0.01, f"frames {i + 1} and {j + 1} are alike (max difference {d:.2e})")
print("engine -a: 3 finite frames, each its own sun, each equal to its plate")
t.done("test_engine_animation")
