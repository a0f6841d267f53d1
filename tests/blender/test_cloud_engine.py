# SPDX-License-Identifier: Apache-2.0
"""The render engine "WELKIN" with clouds (headless, `blender -b file.blend -E WELKIN`): a
procedural layer and a marked VDB sequence (3 frames, written by the test with pyopenvdb).

  * `-f 1` (computed in two tiles of rows): Combined equals `welkin plate --scene` (the
    whole frame at once) on the same scene JSON within 1 % per pixel (relative to max(value, 1e-3 x the image mean): the same core call, so any
    difference is the add-on's); Welkin.Clouds and Welkin.CloudDepth are filled (finite,
    alpha in [0, 1], some cloud in view, CloudDepth 1e10 where alpha is 0).
  * `-a` over frames 1-3: three frames, finite, pairwise different (the volume's density
    grows with the frame: each frame renders its own VDB file).
  * A marked volume whose VDB file is missing: a report naming the object and the path,
    no frame written.
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
CLI = t.ROOT / "build" / "welkin"


def render(blend, out_stem, frames):
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(t.scripts_dir()))
    env.pop("PYTHONPATH", None)
    cmd = [
        *t.blender_command(),
        "-b",
        str(blend),
        "--addons",
        "welkin",
        "-E",
        "WELKIN",
        "-o",
        str(out_stem) + "_####",
        "-F",
        "OPEN_EXR_MULTILAYER",
    ] + frames
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    print(run.stdout[-1200:], run.stderr[-600:])
    return run


def layers(path):
    pixels, names = native.read_exr(str(path))
    out = {}
    for name in ("Combined", "Welkin.Clouds", "Welkin.CloudDepth"):
        cs = [c for c in "RGBAZ" if f"ViewLayer.{name}.{c}" in names]
        out[name] = np.stack([pixels[..., names.index(f"ViewLayer.{name}.{c}")] for c in cs], -1)
    return out


scene, sun = t.new_scene(sun_elevation_deg=25.0, sun_azimuth_deg=30.0, camera_z=20.0)
cam = scene.camera
cam.rotation_euler = (math.radians(95.0), 0.0, math.radians(-90.0))  # along +X, 5 deg up
world = scene.world
world.welkin.method = "lut"
c = world.welkin_clouds
c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 32, 4, 2, 2
ct.add_layer(world, bottom_altitude_m=900.0, top_altitude_m=1600.0, coverage=0.7, density_per_m=0.02)
paths = ct.write_vdb_sequence(t.TMP / "vdb", frames=(1, 2, 3))
vol = ct.add_volume(scene, paths[0], location=(2500.0, 0.0, 450.0))
vol.welkin_cloud.density_scale = 0.01
scene.render.engine = "WELKIN"
# 72 rows: the cloudy plate is computed in two tiles (64 + 8 rows, render_engine.BAND_ROWS).
scene.render.resolution_x, scene.render.resolution_y = 48, 72
scene.render.resolution_percentage = 100
compat.set_file_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER")
scene.render.image_settings.color_depth = "32"
scene.frame_start, scene.frame_end = 1, 3
scene.frame_set(1)

blend = t.TMP / "clouds.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
run = render(blend, t.TMP / "still", ["-f", "1"])
check(run.returncode == 0, "blender -f 1 failed")
got = layers(t.TMP / "still_0001.exr")
cl, cd = got["Welkin.Clouds"], got["Welkin.CloudDepth"][..., 0]
check(
    cl.shape == (72, 48, 4) and np.isfinite(cl).all() and np.isfinite(cd).all(),
    "cloud passes missing or not finite",
)
a = cl[..., 3]
check(
    ((a >= 0) & (a <= 1)).all() and (a > 0.05).mean() > 0.05,
    f"alpha range {a.min()}..{a.max()}, cover {(a > 0.05).mean():.3f}",
)
check((cd[a == 0] == 1e10).all(), "CloudDepth is not 1e10 where there is no cloud")

text = render_engine.scene_description_json(scene, bpy.context.evaluated_depsgraph_get(), native)
scene_path = t.TMP / "still.json"
scene_path.write_text(text)
subprocess.run([str(CLI), "plate", "--scene", str(scene_path), "-o", str(t.TMP / "cli.exr")], check=True)
px, nm = native.read_exr(str(t.TMP / "cli.exr"))
ref = np.stack([px[..., nm.index(c)] for c in "RGB"], -1)
floor = 1e-3 * float(np.abs(ref).mean())
err = np.abs(got["Combined"][..., :3] - ref) / np.maximum(np.abs(ref), floor)
print(
    f"engine with clouds: Combined vs `welkin plate`, max relative error {err.max():.3g}; "
    f"cloud cover {(a > 0.05).mean():.1%}"
)
check(err.max() < 0.01, f"Combined differs from the CLI's plate by {err.max():.3g}")

# -a over 3 frames: each frame its own VDB file.
run = render(blend, t.TMP / "anim", ["-a"])
check(run.returncode == 0, "blender -a failed")
frames = [layers(t.TMP / f"anim_{f:04d}.exr")["Combined"][..., :3] for f in (1, 2, 3)]
for f, img in zip((1, 2, 3), frames):
    check(np.isfinite(img).all() and img.max() > 0, f"frame {f} not finite or black")
for i, j in ((0, 1), (1, 2), (0, 2)):
    d = float(np.abs(frames[i] - frames[j]).max() / np.abs(frames[j]).max())
    check(d > 1e-3, f"frames {i + 1} and {j + 1} are the same (max diff {d:.2e})")
print("engine -a: 3 different, finite frames")

# A missing VDB file: a report, no frame.
vol.data.filepath = str(t.TMP / "vdb" / "gone.0001.vdb")
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
run = render(blend, t.TMP / "missing", ["-f", "1"])
log = run.stdout + run.stderr
check("'Cloud'" in log and "gone.0001.vdb" in log, f"no report naming the volume:\n{log[-1500:]}")
check(not (t.TMP / "missing_0001.exr").exists(), "a frame was written with a missing VDB")
print("engine: a missing VDB is reported, no frame written")
t.done("test_cloud_engine")
