# SPDX-License-Identifier: Apache-2.0
"""Bake for Farm (docs/pipelines.md#bake-for-farm): an animated scene with the Welkin sky
and Aerial Perspective, baked, renders in a Blender without the add-on as the add-on
renders it live, frame by frame; an edit after the bake makes it stale, and the add-on
refuses the stale frames.

The scene: the sun keyed from 12 to 40 degrees over frames 1-3 (the sky, the lamp, the
aerial table and the disc all change), 24 x 12 pixels, Cycles CPU, 2 samples, seed 7.
(a) `blender -b live.blend --addons welkin -a` (the add-on computes every frame) against
    `blender -b baked.blend -a` in a Blender whose user folders hold no add-on (a script
    checks Welkin is not loaded): every frame equal, bit for bit (same inputs, full-float
    lossless images, values keyed exactly); frame 1 and frame 3 differ by far more than
    that (the bake is not the saved frame repeated). With the add-on, the baked file
    renders the same frames too.
(b) The bake writes 4 images (the sky, 3 aerial tables) x 3 frames beside the .blend under welkin_farm/ (relative
    paths), keys the changing values, changes no node of the user's own world nodes or
    material, and refuses an unsaved file with a clear message.
(c) Stale: the sun's frame-3 key moved and the file saved: saving says frames 2-3 are
    stale (frame 2 lies between the keys); a command-line render with the add-on writes
    frame 1, refuses frame 2 (no file for 2 and 3, non-zero exit) on the Blender binary; Blender as a Python module (no Blender SIGINT
    handler, farm.py) prints the refusal. Clear Farm Bake gives the live nodes back.
(d) The files a stock Blender would render wrong (animated without a bake; a stale bake)
    refuse to render there: no frame, non-zero exit ("Cannot render, no camera": the
    add-on saves the camera aside, farm.hide_camera, and puts it back when it is loaded).
(e) A bake that fails part-way (the sun set at frame 3: the disc's nodes change shape)
    says why and keeps nothing: no files, no record, the live nodes.
"""

import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender import farm, farm_bake  # noqa: E402

FRAMES = (1, 2, 3)


def render_anim(blend, out, *, with_addon, expect_ok=True):
    """`blender -b blend -o out/f_#### -a`; returns ({frame: RGB array}, log, exit code)."""
    env, extra = T.command_line_blender(with_addon)
    command = [
        *T.blender_command(),
        "-b",
        "--factory-startup",
        str(blend),
        *extra,
        "-o",
        str(out / "f_####"),
        "-a",
    ]
    print("running:", " ".join(command))
    run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    log = run.stdout + run.stderr
    if expect_ok:
        T.check(run.returncode == 0, f"the render exited {run.returncode}:\n{log[-3000:]}")
        T.check("Traceback" not in log, f"traceback in the render:\n{log[-3000:]}")
    if not with_addon:
        T.check(T.NO_WELKIN_SAYS in log, f"the check did not run:\n{log[-2000:]}")
    frames = {}
    for f in FRAMES:
        path = out / f"f_{f:04d}.exr"
        if path.is_file():
            pixels, names = welkin.read_exr(str(path))
            frames[f] = np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)
    return frames, log, run.returncode


def user_nodes():
    """The user's own nodes of the world and the ground material: name -> input values."""
    out = {}
    trees = [("world", bpy.context.scene.world.node_tree), ("ground", bpy.data.materials["Ground"].node_tree)]
    for kind, tree in trees:
        for n in tree.nodes:
            if n.get("welkin_role") or n.get("welkin_aerial"):
                continue
            out[f"{kind}/{n.name}"] = [
                repr(tuple(s.default_value) if hasattr(s.default_value, "__len__") else s.default_value)
                for s in n.inputs
                if hasattr(s, "default_value")
            ]
    return out


# --- the scene ---------------------------------------------------------------------------
scene, sun = T.new_scene(12.0, 60.0, resolution="256", camera_z=30.0)
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 2
scene.cycles.seed = 7
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 24, 12
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.frame_start, scene.frame_end = FRAMES[0], FRAMES[-1]
bpy.ops.mesh.primitive_plane_add(size=200000.0)
ground = bpy.data.materials.new("Ground")
ground.use_nodes = True
bpy.context.active_object.data.materials.append(ground)
cam = scene.camera
cam.rotation_euler = (1.45, 0.0, -1.5708)  # nearly level, looking along +X: ground and sky
cam.data.clip_end = 1e6
bpy.ops.welkin.update_sky()
T.check(scene.world.welkin.active, scene.world.welkin.status)
scene.welkin_aerial.enabled = True
sun.keyframe_insert("rotation_quaternion", frame=1)
T.aim_sun(sun, 40.0, 60.0)
sun.keyframe_insert("rotation_quaternion", frame=3)
scene.frame_set(1)

# (b) An unsaved file cannot be baked: the images go beside it.
try:
    bpy.ops.welkin.bake_farm()
    T.check(False, "an unsaved file was baked")
except RuntimeError as error:
    T.check("save the .blend first" in str(error), f"unclear refusal: {error}")

live_blend = T.TMP / "live.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(live_blend))
before = user_nodes()

# --- the bake ----------------------------------------------------------------------------
baked_blend = T.TMP / "baked.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(baked_blend))
T.check(bpy.ops.welkin.bake_farm() == {"FINISHED"}, "Bake for Farm did not finish")
rec = farm_bake.record(bpy.context.scene)
T.check(rec is not None and sorted(rec["frames"]) == ["1", "2", "3"], f"the bake's record: {rec}")
files = sorted(p.relative_to(T.TMP).as_posix() for p in (T.TMP / "welkin_farm").rglob("*.exr"))
print(f"(b) written: {files}; keyed {len(rec['keyed'])} values: {rec['keyed'][:6]} ...")
T.check(len(files) == 4 * len(FRAMES), f"expected 4 images (sky, 3 aerial) x {len(FRAMES)} frames: {files}")
for _kind, _tree, _node, _live, farm_name in rec["images"]:
    image = bpy.data.images[farm_name]
    T.check(
        image.source == "SEQUENCE" and image.filepath.startswith("//welkin_farm/"),
        f"{farm_name}: {image.filepath}",
    )
T.check(any(k.startswith("lamp\t") for k in rec["keyed"]), f"the lamp is not keyed: {rec['keyed']}")
T.check(any(k.startswith("world\t") for k in rec["keyed"]), f"the disc is not keyed: {rec['keyed']}")
T.check(user_nodes() == before, "the bake changed the user's own nodes")
T.check(bpy.context.scene.frame_current == 1, "the bake did not put the current frame back")
bpy.ops.wm.save_mainfile()
T.check("stale" not in bpy.context.scene.welkin_aerial.status, bpy.context.scene.welkin_aerial.status)

# (a) A stock Blender renders the baked file as the add-on renders the live one.
live, _log, _rc = render_anim(live_blend, T.TMP / "live_out", with_addon=True)
stock, _log, _rc = render_anim(baked_blend, T.TMP / "stock_out", with_addon=False)
T.check(
    sorted(live) == list(FRAMES) and sorted(stock) == list(FRAMES), f"frames: {sorted(live)} {sorted(stock)}"
)
motion = float(np.abs(live[3] - live[1]).max())
print(f"(a) frame 3 vs frame 1 (the animation): max |diff| {motion:.3g} of max {float(live[3].max()):.3g}")
T.check(motion > 0.05 * float(live[3].max()), f"the frames barely change: {motion}")
for f in FRAMES:
    T.check(np.isfinite(stock[f]).all() and stock[f].max() > 0.0, f"stock frame {f} is empty")
    diff = float(np.abs(stock[f] - live[f]).max())
    print(f"(a) frame {f}: stock (baked) vs add-on (live): max |diff| {diff:.3g}")
    T.check(np.array_equal(stock[f], live[f]), f"frame {f}: the stock render differs: max |diff| {diff}")
addon_baked, _log, _rc = render_anim(baked_blend, T.TMP / "addon_baked_out", with_addon=True)
for f in FRAMES:
    T.check(np.array_equal(addon_baked[f], live[f]), f"frame {f}: the add-on's render of the bake differs")
print("(a) every frame: the stock Blender equals the add-on, bit for bit")

# (c) An edit after the bake: the bake is stale for frame 3.
bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
scene = bpy.context.scene
sun = scene.objects["Sun"]
T.aim_sun(sun, 25.0, 60.0)
sun.keyframe_insert("rotation_quaternion", frame=3)
scene.frame_set(1)
stale_blend = T.TMP / "stale.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(stale_blend))
status = scene.welkin_aerial.status
print(f"(c) saving: {status}")
# Frame 2 too: the sun between the keys of frames 1 and 3 moved with the key of frame 3.
T.check("stale for frames 2-3" in status, f"saving a stale bake does not say so: {status!r}")
out = T.TMP / "stale_out"
frames, log, code = render_anim(stale_blend, out, with_addon=True, expect_ok=False)
T.check("Bake for Farm: the farm bake of frame 2 is stale" in log, f"frame 2 not refused:\n{log[-3000:]}")
T.check(
    1 in frames and np.array_equal(frames[1], live[1]),
    f"frame 1 (still current) is not rendered: {sorted(frames)}",
)
if not T.is_module_bpy():
    T.check(
        code != 0 and sorted(frames) == [1], f"a stale frame rendered: exit {code}, frames {sorted(frames)}"
    )
    print(f"(c) the add-on refuses the stale frame: exit {code}, frames {sorted(frames)}")
else:
    print(f"(c) the add-on refuses the stale frame (printed; bpy has no Blender SIGINT handler): exit {code}")

# (d) Files a stock Blender would render wrong refuse to render there: the animated file
# saved without a bake, and the stale bake (the scene's camera is kept for the add-on).
T.check(scene.camera is not None and scene.camera.name == "Camera", "saving lost the scene's camera")
for blend in (live_blend, stale_blend):
    out = T.TMP / f"refused_{blend.stem}"
    frames, log, code = render_anim(blend, out, with_addon=False, expect_ok=False)
    print(f"(d) {blend.name} in a stock Blender: exit {code}, frames {sorted(frames)}")
    T.check(code != 0 and not frames, f"{blend.name} rendered without the add-on: exit {code}\n{log[-2000:]}")
    T.check("no camera" in log.lower(), f"{blend.name}: not refused for the camera:\n{log[-2000:]}")
# With the add-on the camera is back at once (the live renders of (a) and (c) above), and
# in a file opened where the add-on is enabled.
bpy.ops.wm.open_mainfile(filepath=str(live_blend))
T.check(bpy.context.scene.camera is not None, "the camera is not back after opening the file")
T.check(farm.CAMERA_KEPT not in bpy.context.scene, "the kept camera property stayed")
bpy.ops.wm.open_mainfile(filepath=str(stale_blend))

# Clear Farm Bake: the live nodes back, the keys gone.
bpy.ops.welkin.clear_farm_bake()
scene = bpy.context.scene
T.check(farm_bake.record(scene) is None, "the bake is still there")
sky_node = next(n for n in scene.world.node_tree.nodes if n.get("welkin_role") == "sky_texture")
T.check(sky_node.image == scene.world.welkin.sky_image, f"the sky node reads {sky_node.image}")
T.check(not any(i.get(farm_bake.MARK) for i in bpy.data.images), "farm images left in the file")
for id_ in (scene.world.node_tree, scene.objects["Sun"].data):
    data = id_.animation_data
    T.check(data is None or data.action is None, f"{id_.name} keeps the bake's action")
print("(c) Clear Farm Bake: the live nodes are back")

# (e) A bake that fails on a later frame keeps nothing: the sun set below the horizon at
# frame 3 takes the disc's link away (a shape keys cannot hold), the files of frames 1-2
# are removed, no record, the nodes read the live images.
scene = bpy.context.scene
sun = scene.objects["Sun"]
T.aim_sun(sun, -10.0, 60.0)
sun.keyframe_insert("rotation_quaternion", frame=3)
scene.frame_set(1)
(T.TMP / "failing").mkdir()
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "failing" / "failing.blend"))
before = user_nodes()
try:
    bpy.ops.welkin.bake_farm()
    T.check(False, "a bake whose nodes change shape finished")
except RuntimeError as error:
    print(f"(e) {error}")
    T.check("change shape" in str(error) and "nothing kept" in str(error), f"unclear failure: {error}")
left = sorted(p.name for p in (T.TMP / "failing").rglob("*.exr"))
T.check(not left, f"a failed bake left files: {left}")
T.check(farm_bake.record(scene) is None, "a failed bake left a record")
sky_node = next(n for n in scene.world.node_tree.nodes if n.get("welkin_role") == "sky_texture")
T.check(
    sky_node.image == scene.world.welkin.sky_image, f"after a failed bake the sky node reads {sky_node.image}"
)
T.check(user_nodes() == before and scene.frame_current == 1, "a failed bake changed the scene")

T.done("test_farm_bake")
