# SPDX-License-Identifier: Apache-2.0
"""A saved file with Aerial Perspective on renders right in a Blender without the add-on
(docs/pipelines.md#saved-files-without-the-add-on): saving bakes the frame's table and
packs its images, so a farm's stock Blender (add-on not installed, Python scripts of the
file not run) renders the frame the add-on renders, bit for bit (Cycles, fixed seed and
sample count, CPU).

(a) A static scene (camera, sun and atmosphere the same on every frame): `blender -b
    file.blend -o ... -f 1` with the add-on and without it (a separate Blender whose
    user folders hold no add-on; a script checks that Welkin is not loaded) give the same
    pixels, and frame 3 of the stock render equals frame 1 of the add-on's (the scene does
    not change). The haze is there: the file saved with Aerial Perspective off renders
    differently; that file (the sky alone) renders the same with and without the add-on.
(b) The table's images are packed in the file, as float OpenEXR (they reload unchanged),
    not 1 x 1 generated images.
(c) Saving a scene whose sun is animated (no farm bake) says, in the panel's status line,
    that the file renders right only with the add-on and that a stock Blender refuses it:
    the file on disk has no scene camera, the camera kept for the add-on, which puts it
    back after saving (tests/blender/test_farm_bake.py renders such files).
(d) Write Pass Files follows `-o`: `blender -b file.blend -o /elsewhere/f_#### -f 1`
    writes the depth file and the passes under /elsewhere, nothing at the saved path.
Runs on every Blender of scripts/test_blender.sh (the binary's command line, or
tests/blender/bpy_blender.py for PyPI's bpy).
"""

import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender.aerial import frame as aerial_frame  # noqa: E402


def render(blend, out, frame, *, with_addon):
    env, extra = T.command_line_blender(with_addon)
    command = [
        *T.blender_command(),
        "-b",
        "--factory-startup",
        str(blend),
        *extra,
        "-o",
        str(out / "f_####"),
        "-f",
        str(frame),
    ]
    print("running:", " ".join(command))
    run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=400)
    log = run.stdout + run.stderr
    T.check(run.returncode == 0, f"the render exited {run.returncode}:\n{log[-3000:]}")
    T.check("Traceback" not in log, f"traceback in the render:\n{log[-3000:]}")
    if not with_addon:
        T.check(T.NO_WELKIN_SAYS in log, f"the check did not run:\n{log[-2000:]}")
    path = out / f"f_{frame:04d}.exr"
    T.check(path.is_file(), f"no frame {path}:\n{log[-2000:]}")
    pixels, names = welkin.read_exr(str(path))
    return np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)


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
scene.frame_start, scene.frame_end = 1, 3
bpy.ops.mesh.primitive_plane_add(size=200000.0)
ground = bpy.data.materials.new("Ground")
ground.use_nodes = True
bpy.context.active_object.data.materials.append(ground)
cam = scene.camera
cam.rotation_euler = (1.45, 0.0, -1.5708)  # nearly level, looking along +X
cam.data.clip_end = 1e6
bpy.ops.welkin.update_sky()
T.check(scene.world.welkin.active, scene.world.welkin.status)
scene.welkin_aerial.enabled = True

blend = T.TMP / "static.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
T.check(
    "farms with the add-on only" not in scene.welkin_aerial.status,
    f"a static scene saved with a warning: {scene.welkin_aerial.status}",
)

# (b) The images in the file: packed float EXR at the table's size.
names = aerial_frame.SCREEN_IMAGES
sizes = {n: tuple(bpy.data.images[n].size) for n in names}
bpy.ops.wm.open_mainfile(filepath=str(blend))
for name in names:
    image = bpy.data.images.get(name)
    T.check(image is not None, f"no image {name} in the saved file")
    T.check(image.packed_file is not None, f"{name} is not packed in the file")
    T.check(
        tuple(image.size) == sizes[name] and image.size[0] > 1,
        f"{name}: {tuple(image.size)} in the file, {sizes[name]} baked",
    )
    T.check(image.is_float, f"{name} reloads as 8-bit")
print(f"(b) the table's images are packed: {sizes}")

# (a) The same frame with and without the add-on.
with_addon = render(blend, T.TMP / "addon", 1, with_addon=True)
stock = render(blend, T.TMP / "stock_out", 1, with_addon=False)
T.check(np.isfinite(stock).all() and stock.max() > 0.0, "the stock render is empty")
diff = float(np.abs(stock - with_addon).max())
print(f"(a) stock vs add-on, frame 1: max |diff| {diff:.3g} of max {float(with_addon.max()):.3g}")
T.check(np.array_equal(stock, with_addon), f"the stock render differs from the add-on's: {diff}")
stock3 = render(blend, T.TMP / "stock_out", 3, with_addon=False)
T.check(np.array_equal(stock3, with_addon), "frame 3 of the static scene differs from frame 1")

# The haze is in the frame: the same file with Aerial Perspective off differs.
bpy.ops.wm.open_mainfile(filepath=str(blend))
bpy.context.scene.welkin_aerial.enabled = False
plain_blend = T.TMP / "plain.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(plain_blend))
plain = render(plain_blend, T.TMP / "plain_out", 1, with_addon=False)
haze = float(np.abs(plain - with_addon).max())
print(f"(a) hazed vs not: max |diff| {haze:.3g}")
T.check(haze > 0.01 * float(with_addon.max()), f"the haze is missing: max |diff| {haze}")
# The sky alone (aerial perspective off): the packed sky renders as the add-on's.
plain_addon = render(plain_blend, T.TMP / "plain_addon", 1, with_addon=True)
T.check(
    np.array_equal(plain, plain_addon),
    "the sky-only file renders differently without "
    f"the add-on: max |diff| {float(np.abs(plain - plain_addon).max())}",
)
print("(a) a stock Blender renders the saved file as the add-on does, bit for bit")

# (c) An animated sun: saving says the file needs the add-on on the farm.
bpy.ops.wm.open_mainfile(filepath=str(blend))
scene = bpy.context.scene
sun = scene.objects["Sun"]
sun.keyframe_insert("rotation_quaternion", frame=1)
T.aim_sun(sun, 20.0, 60.0)
sun.keyframe_insert("rotation_quaternion", frame=3)
scene.frame_set(1)
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "animated.blend"))
status = scene.welkin_aerial.status
T.check(
    "farms with the add-on only" in status and "sun lamp 'Sun'" in status,
    f"saving an animated sun does not say it needs the add-on: {status!r}",
)
T.check("refuses to render" in status, f"saving does not say a stock Blender refuses it: {status!r}")
T.check(scene.camera is not None and scene.camera.name == "Camera", "saving lost the scene's camera")
print(f"(c) saving an animated scene: {status}")

# (d) Write Pass Files follows -o: the depth file and the passes go beside the frames of
# the command line's output path, not the saved one.
bpy.ops.wm.open_mainfile(filepath=str(blend))
scene = bpy.context.scene
scene.render.filepath = str(T.TMP / "saved" / "f_####")
scene.welkin_aerial.side_files = True
passes_blend = T.TMP / "passes.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(passes_blend))
elsewhere = T.TMP / "elsewhere"
render(passes_blend, elsewhere, 1, with_addon=True)
written = sorted(p.name for p in elsewhere.iterdir())
for name in ("f_welkin_render_0001.exr", "f_welkin_aerial_0001.exr", "f_welkin_scene_0001.json"):
    T.check(name in written, f"{name} is not beside the frame of -o: {written}")
saved = T.TMP / "saved"
T.check(
    not saved.exists(),
    "files were written at the saved output path: "
    f"{sorted(p.name for p in saved.iterdir()) if saved.exists() else []}",
)
print(f"(d) Write Pass Files follows -o: {written}")

T.done("test_farm_saved_file")
