# SPDX-License-Identifier: Apache-2.0
"""A keyed wind offset and evolution move and reshape the clouds in command-line animation
renders (`blender -b file.blend -a`), in the Cycles world and in the Welkin engine.

A cloud layer's wind offset is keyed (frame 1: 0 m, frame 2: 3 km along +X), and its
evolution (frame 1: 0 m, frame 2: 400 m through the noise's height). The file is
saved and rendered by a separate headless Blender with `-a` over frames 1-2, once with
Cycles (a panoramic camera at the origin: the frame is the world's cloudy sky) and once
with the Welkin engine (a camera looking along +X, 8 degrees up). Each frame must be that
frame's clouds:

  * its own: frames 1 and 2 differ by more than 5 % of the frame's peak somewhere (clouds
    that stand still give two identical frames; the sun and the sky do not move);
  * the per-frame reference, in this session after scene.frame_set(f) (the path that
    always moved the clouds): Cycles, rendered here from the world Update Sky made for
    that frame, same seed and samples: every pixel within 1e-3 relative (of max(value,
    1e-3 x the frame's mean)); Welkin, welkin.camera_plate on that frame's scene JSON
    (the core call `welkin plate --scene` makes): within 1 %, as test_engine_animation;
  * the evolution's own share: Cycles' per-frame render of frame 2 with the evolution's
    frame-2 key removed (the wind alone) differs from the `-a` frame by more than 1 % of
    the peak, so the `-a` frame took the keyed evolution too.

Run: PYTHONPATH=$PWD/build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_cloud_wind_animation.py
"""

import math
import os
import pathlib
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402
import cloud_testing as ct  # noqa: E402

addon, native = t.install_addon()
from welkin.blender import compat  # noqa: E402
from welkin.blender.engine import render_engine  # noqa: E402

check = t.check
W, H = 64, 32

scene, sun = t.new_scene(sun_elevation_deg=30.0, sun_azimuth_deg=40.0, camera_z=2.0)
world = scene.world
c = ct.quick_cloudy_world(world)
layer = ct.add_layer(
    world,
    bottom_altitude_m=1000.0,
    top_altitude_m=1800.0,
    coverage=0.6,
    density_per_m=0.02,
    base_scale_m=3000.0,
    weather_scale_m=12000.0,
)
layer.wind_offset_m = (0.0, 0.0)
layer.keyframe_insert("wind_offset_m", frame=1)
layer.wind_offset_m = (3000.0, 0.0)
layer.keyframe_insert("wind_offset_m", frame=2)
layer.evolution_m = 0.0
layer.keyframe_insert("evolution_m", frame=1)
layer.evolution_m = 400.0
layer.keyframe_insert("evolution_m", frame=2)
scene.frame_start, scene.frame_end = 1, 2
scene.frame_set(1)
check(tuple(layer.wind_offset_m) == (0.0, 0.0), f"keyed wind at frame 1: {layer.wind_offset_m[:]}")
t.panoramic_camera(scene, W, H, samples=1)
scene.cycles.seed = 3
bpy.ops.welkin.update_sky()
blend = t.TMP / "wind.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))

env = dict(os.environ, BLENDER_USER_SCRIPTS=str(t.scripts_dir()))
env.pop("PYTHONPATH", None)


def render_anim(stem, extra):
    cmd = t.blender_command() + ["-b", str(blend), "--addons", "welkin"]
    run = subprocess.run(
        cmd + extra + ["-o", str(t.TMP / f"{stem}_####"), "-a"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    print(run.stdout[-800:], run.stderr[-400:])
    check(run.returncode == 0, f"{stem}: blender -a exited {run.returncode}")
    return [t.read_rgb_exr(native, t.TMP / f"{stem}_{f:04d}.exr") for f in (1, 2)]


def relative(a, ref):
    return np.abs(a - ref) / np.maximum(np.abs(ref), 1e-3 * float(np.abs(ref).mean()))


def distinct(frames, what):
    d = float(np.abs(frames[0] - frames[1]).max() / np.abs(frames[1]).max())
    print(f"{what}: frames 1 and 2 differ by {d:.3f} of the peak")
    check(
        d > 0.05,
        f"{what}: frames 1 and 2 are alike (max difference {d:.2e} of the peak): "
        f"the keyed wind did not move the clouds",
    )


# --- Cycles: the world's cloudy sky.
cycles = render_anim("cycles", [])
distinct(cycles, "Cycles -a")
for f, img in zip((1, 2), cycles):
    scene.frame_set(f)
    bpy.ops.welkin.update_sky()
    t.render_still(scene, t.TMP / f"cycles_ref_{f}.exr")
    ref = t.read_rgb_exr(native, t.TMP / f"cycles_ref_{f}.exr")
    err = relative(img, ref)
    print(f"Cycles frame {f}: max relative difference from the per-frame render {err.max():.2e}")
    check(
        np.isfinite(img).all() and err.max() < 1e-3,
        f"Cycles frame {f}: differs from the frame_set render by {err.max():.3g}",
    )

# The evolution's share: frame 2 without its evolution key (the wind alone).
layer.keyframe_delete("evolution_m", frame=2)
scene.frame_set(2)
check(layer.evolution_m == 0.0, f"evolution without its frame-2 key: {layer.evolution_m}")
bpy.ops.welkin.update_sky()
t.render_still(scene, t.TMP / "cycles_wind_only_2.exr")
wind_only = t.read_rgb_exr(native, t.TMP / "cycles_wind_only_2.exr")
d = float(np.abs(cycles[1] - wind_only).max() / np.abs(cycles[1]).max())
print(f"Cycles frame 2: the keyed evolution changes it by {d:.3f} of the peak")
check(d > 0.01, f"frame 2 with and without the keyed evolution differ by only {d:.2e} of the peak")
layer.evolution_m = 400.0
layer.keyframe_insert("evolution_m", frame=2)

# --- The Welkin engine: the camera plate with the clouds.
cam = scene.camera
cam.data.type = "PERSP"
cam.rotation_euler = (math.radians(98.0), 0.0, math.radians(-90.0))  # +X, 8 degrees up
cam.data.clip_end = 1e6
scene.render.engine = "WELKIN"
scene.render.resolution_x, scene.render.resolution_y = 48, 32
compat.set_file_format(scene.render.image_settings, "OPEN_EXR")
scene.frame_set(1)
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
plates = render_anim("welkin", ["-E", "WELKIN"])
distinct(plates, "Welkin engine -a")
for f, img in zip((1, 2), plates):
    scene.frame_set(f)
    text = render_engine.scene_description_json(scene, bpy.context.evaluated_depsgraph_get(), native)
    ref = native.camera_plate(text)["combined"][..., :3]
    err = relative(img, ref)
    print(f"Welkin frame {f}: max relative difference from its plate {err.max():.2e}")
    check(
        np.isfinite(img).all() and err.max() < 0.01,
        f"Welkin frame {f}: differs from the plate by {err.max():.3g}",
    )
t.done("test_cloud_wind_animation")
