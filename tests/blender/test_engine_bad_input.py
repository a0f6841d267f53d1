# SPDX-License-Identifier: Apache-2.0
"""The render engine "WELKIN" refuses what it cannot render with a clear report and
writes no frame: no camera, a camera below the ground, a render region. Rendered headless
(`blender -b scene.blend -E WELKIN -f 1`, the add-on enabled with --addons)."""

import os
import pathlib
import subprocess
import sys

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as t  # noqa: E402

addon, native = t.install_addon()
check = t.check


def render_headless(blend, out_stem):
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
        "-f",
        "1",
    ]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    print(run.stdout[-1200:], run.stderr[-800:])
    return pathlib.Path(str(out_stem) + "_0001.exr"), run.stdout + run.stderr


def expect_refusal(name, words):
    blend = t.TMP / f"{name}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    exr, log = render_headless(blend, t.TMP / name)
    check(all(w in log for w in words), f"{name}: report {words} missing from:\n{log[-1500:]}")
    check(not exr.exists(), f"{name}: a frame was written ({exr})")
    print(f"{name}: refused with a report, no frame written")


scene, _sun = t.new_scene(camera_z=-20.0)
scene.render.engine = "WELKIN"
scene.render.resolution_x, scene.render.resolution_y = 32, 16
expect_refusal("below_ground", ("camera.matrix_world", "below the ground"))

scene.camera.location.z = 2.0
scene.render.use_border = True
expect_refusal("border", ("render region",))
scene.render.use_border = False

scene.camera = None
# Blender itself refuses before the engine runs ("Cannot render, no camera"); the
# engine's own report ("no active camera") covers scripts that call it otherwise.
expect_refusal("no_camera", ("no camera",))
t.done("test_engine_bad_input")
