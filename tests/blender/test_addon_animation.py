# SPDX-License-Identifier: Apache-2.0
"""(d) An animated sun gives a different sky on frames 1 and 10 of an `-a` render: the
file is saved with the add-on's live sky, then rendered by a separate headless Blender
(`blender -b file.blend --addons welkin -s 1 -e 19 -j 9 -a`: frames 1, 10, 19; the sun moves
until frame 10 and holds, so frame 19 also takes the path where the sky is current), where
only the persistent frame-change handler can update the world. Each frame must match the module's sky for the
lamp's direction at that frame (as Blender evaluates the animation), under the error
measure and tolerances of test_addon_render (b): median 0.1 %, 99.5th percentile 1 %, on
the upper hemisphere away from the sun; and the two frames must differ by far more.
The lamp must follow too, in the render itself: a white diffuse plane below the camera,
lit by the sun lamp alone (the world is invisible to diffuse rays here), has the radiance
albedo / pi x strength x colour x sin(sun elevation) of the lamp the add-on computes for
that frame; asserted within 2 % (Monte-Carlo noise of 4 samples on a shadow-free plane is
far smaller; the previous frame's lamp would miss by tens of percent).
In this session the same handler runs on frame_set, which also syncs the lamp.
"""

import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender import compat  # noqa: E402

W, H = 256, 128
scene, sun = T.new_scene(40.0, 30.0, resolution=str(W))
T.panoramic_camera(scene, W, H, samples=4)
scene.frame_start, scene.frame_end = 1, 19
scene.frame_set(1)
T.aim_sun(sun, 40.0, 30.0)
sun.keyframe_insert("rotation_quaternion", frame=1)
T.aim_sun(sun, 8.0, 150.0)
sun.keyframe_insert("rotation_quaternion", frame=10)
scene.frame_set(1)
bpy.ops.welkin.update_sky()
ALBEDO = 0.8
bpy.ops.mesh.primitive_plane_add(size=2000.0, location=(0.0, 0.0, -1.0))
plane_material = bpy.data.materials.new("White")
nodes = compat.material_node_tree(plane_material).nodes
nodes.remove(nodes["Principled BSDF"])
lambert = nodes.new("ShaderNodeBsdfDiffuse")  # roughness 0: Lambert
lambert.inputs["Color"].default_value = (ALBEDO, ALBEDO, ALBEDO, 1.0)
plane_material.node_tree.links.new(lambert.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
bpy.context.active_object.data.materials.append(plane_material)
scene.world.cycles_visibility.diffuse = False
scene.world.cycles_visibility.glossy = False

# The lamp's direction at frames 1 and 10 as Blender evaluates the animation; and the
# handler at work in this session (sky and lamp follow frame_set).
atm = welkin.Atmosphere.preset(welkin.Atmosphere.preset_names()[0])  # the add-on's default
directions = {}
for f in (1, 10, 19):
    scene.frame_set(f)
    z = sun.matrix_world.col[2]
    directions[f] = (z[0], z[1], z[2])
    expected = max(welkin.sun(atm, 0.0, directions[f]).direct_irradiance_rgb)
    T.check(
        math.isclose(sun.data.energy, expected, rel_tol=1e-5),
        f"frame {f}: lamp {sun.data.energy} W/m^2, expected {expected}",
    )
scene.frame_set(1)

scene.render.filepath = str(T.TMP / "frames" / "f_####")
blend = T.TMP / "animated.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))

env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
env["BLENDER_USER_SCRIPTS"] = str(T.scripts_dir())
env["BLENDER_USER_CONFIG"] = str(T.TMP / "config")
command = [
    *T.blender_command(),
    "-b",
    "--factory-startup",
    str(blend),
    "--addons",
    "welkin",
    "-s",
    "1",
    "-e",
    "19",
    "-j",
    "9",
    "-a",
]
print("running:", " ".join(command))
run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
log = run.stdout + run.stderr
T.check(run.returncode == 0, f"-a render failed ({run.returncode}):\n{log[-3000:]}")
T.check("Traceback" not in log, f"traceback in the -a render:\n{log[-3000:]}")

frames = {f: T.read_rgb_exr(welkin, T.TMP / "frames" / f"f_{f:04d}.exr") for f in (1, 10, 19)}
jj, ii = np.mgrid[0:H, 0:W]


def compare(render, f):
    u, v = welkin.direction_to_equirect(np.array(directions[f]))
    i_s, j_s = int(u * W), int((1.0 - v) * H)
    near_sun = (np.abs(jj - j_s) <= 3) & (np.minimum(np.abs(ii - i_s), W - np.abs(ii - i_s)) <= 3)
    upper = (jj < H // 2) & ~near_sun
    ref = welkin.sky_image(atm, 0.0, directions[f], W, "auto")  # the add-on's default method
    floor = 0.01 * float(ref[upper].mean())
    e = (np.abs(render - ref) / (ref + floor)).max(axis=2)[upper]
    return float(np.median(e)), float(np.percentile(e, 99.5))


for f in (1, 10, 19):
    median, p995 = compare(frames[f], f)
    print(
        f"(d) frame {f}: render vs module sky for the lamp at frame {f}: median {median:.4%}, "
        f"99.5th percentile {p995:.4%}"
    )
    T.check(median < 0.001 and p995 < 0.01, f"frame {f} does not show its sun's sky")
    other = 1 if f > 1 else 19
    median, _ = compare(frames[other], f)
    T.check(median > 0.1, f"frame {other} looks like frame {f}'s sky ({median:.2%})")
print("(d) frames 1, 10 and 19 of the -a render show their own skies")

# The lamp, frame by frame: the ground straight below (the bottom rows, nadir side).
for f in (1, 10, 19):
    rgb = np.asarray(welkin.sun(atm, 0.0, directions[f]).direct_irradiance_rgb)
    sin_e = directions[f][2] / np.linalg.norm(directions[f])
    expected = ALBEDO / math.pi * rgb * sin_e
    ground = frames[f][H - H // 8 :].reshape(-1, 3).mean(axis=0)
    print(f"(d) frame {f}: ground below {ground}, lamp-lit expectation {expected}")
    T.check(np.allclose(ground, expected, rtol=0.02), f"frame {f}: the lamp is not this frame's")


T.done("test_addon_animation")
