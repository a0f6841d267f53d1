# SPDX-License-Identifier: Apache-2.0
"""A frame the add-on could not prepare fails a command-line render visibly (issue 18,
item 3): `blender -b file.blend --addons welkin -a` in a separate Blender, as a farm runs it.

(a) The sky: a VDB sequence (frames 1, 2, 4; frame 3's file missing) marked as a Welkin
    cloud, the world's cloudy sky following every frame, placeholders on. Frames 1 and 2
    are written; the render stops at frame 3 with "sky not updated" and the reason; no
    file for frames 3 and 4 (the placeholder of frame 3 is gone too); exit status
    non-zero. With frame 3's file in place the same render writes all four and exits 0;
    failing again over that complete run, it leaves frames 1 and 2 (rewritten) and none of
    the earlier run's frames 3 and 4.
(b) The aerial perspective, failing after the frame was saved (render_post follows the
    save): a foreign file where frame 2's aerial passes go. Frame 1 and its passes are
    written; frame 2's image is removed again, frame 3 is not rendered; exit non-zero.
(c) The aerial perspective, failing before the frame renders (frame_change_post): the
    missing VDB frame with aerial on and no Welkin sky: frames 1 and 2 written, frame 3
    not; exit non-zero.
(d) The Welkin render engine with the missing VDB frame: its ERROR report makes Blender
    cancel the render (no file for frame 3) and exit non-zero.
Blender stops the way Ctrl-C stops a background render (farm.py).
"""

import os
import pathlib
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_testing as T  # noqa: E402

if T.is_module_bpy():
    T.skip(
        "test_addon_farm",
        "a failed frame stops a command-line render through the Blender "
        "binary's own SIGINT handler (creator_signals), which Blender as a Python module "
        "(PyPI's bpy) does not install: there Python owns SIGINT and farm.py raises nothing",
    )

import cloud_testing as C  # noqa: E402

import bpy  # noqa: E402

addon, welkin = T.install_addon()
from welkin.blender.aerial import scene as aerial  # noqa: E402
from welkin import scene_export  # noqa: E402


def render(blend, last_frame):
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
        str(last_frame),
        "-a",
    ]
    print("running:", " ".join(command))
    run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=400)
    log = run.stdout + run.stderr
    T.check("Traceback" not in log, f"traceback in the -a render:\n{log[-3000:]}")
    return run.returncode, log


def frames_on_disk(directory):
    return sorted(p.name for p in pathlib.Path(directory).glob("f_*.png"))


scene, sun = T.new_scene(30.0, 40.0, resolution="256")
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 1
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 16, 8
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.frame_start, scene.frame_end = 1, 4
world = scene.world
world.welkin.method = "lut"
c = world.welkin_clouds
c.max_steps, c.light_steps, c.ambient_steps, c.octaves = 16, 2, 1, 1
c.volumes_in_world = True  # the world's sky reads the VDB of each frame
vdb_dir = T.TMP / "vdb"
paths = C.write_vdb_sequence(vdb_dir, frames=(1, 2, 3, 4), size=8)
missing = paths[2]
missing.rename(missing.with_suffix(".kept"))
volume = C.add_volume(scene, paths[0], sequence=4)
scene.frame_set(1)
bpy.ops.welkin.update_sky()
T.check(world.welkin.active and "with clouds" in world.welkin.status, world.welkin.status)

# (a) The sky of frame 3 cannot be made.
out = T.TMP / "a"
scene.render.filepath = str(out / "f_####")
scene.render.use_placeholder = True
blend = T.TMP / "sky.blend"
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
rc, log = render(blend, 4)
print("\n".join(line for line in log.splitlines() if "Welkin" in line))
T.check(rc != 0, f"the -a render exited {rc} with frame 3's sky not updated:\n{log[-3000:]}")
T.check(
    "sky not updated" in log and missing.name in log,
    f"the log does not say why frame 3 failed:\n{log[-3000:]}",
)
T.check("frame 3 failed" in log, f"the log does not name the failed frame:\n{log[-3000:]}")
T.check(
    frames_on_disk(out) == ["f_0001.png", "f_0002.png"],
    f"frames on disk: {frames_on_disk(out)}, expected 1 and 2 only",
)
# The control: with the file back, the same render succeeds.
missing.with_suffix(".kept").rename(missing)
out_ok = T.TMP / "a_ok"
scene.render.filepath = str(out_ok / "f_####")
bpy.ops.wm.save_as_mainfile(filepath=str(blend))
rc, log = render(blend, 4)
T.check(rc == 0, f"the render with every VDB frame exited {rc}:\n{log[-3000:]}")
T.check(
    frames_on_disk(out_ok) == [f"f_{f:04d}.png" for f in (1, 2, 3, 4)],
    f"frames on disk: {frames_on_disk(out_ok)}",
)
# A failed run over an earlier complete one: the earlier run's frames 3 and 4 go (the
# render failed at frame 3 and was to write 4), frames 1 and 2 are this run's.
earlier = time.time() - 3600.0
for path in out_ok.glob("f_*.png"):
    os.utime(path, (earlier, earlier))
missing.rename(missing.with_suffix(".kept"))
rc, log = render(blend, 4)
T.check(rc != 0, f"the -a render exited {rc} with frame 3's sky not updated:\n{log[-3000:]}")
T.check(
    frames_on_disk(out_ok) == ["f_0001.png", "f_0002.png"],
    f"frames on disk after a failed run over an earlier one: {frames_on_disk(out_ok)}",
)
T.check(
    all((out_ok / f"f_{f:04d}.png").stat().st_mtime > earlier + 1800.0 for f in (1, 2)),
    "frames 1 and 2 are not this run's",
)
T.check("an earlier run's frame" in log, f"the log does not say what was removed:\n{log[-3000:]}")
missing.with_suffix(".kept").rename(missing)
print(
    "(a) a frame whose sky failed stops the -a render: exit non-zero, no file for it "
    "(nor an earlier run's for it and the frames after it)"
)

# (b) The aerial perspective of frame 2 fails after the frame was saved.
bpy.ops.welkin.remove_sky()
bpy.data.objects.remove(volume)
scene.render.use_placeholder = False
out = T.TMP / "b"
scene.render.filepath = str(out / "f_####")
scene.welkin_aerial.side_files = True  # the pass files beside the render
scene.welkin_aerial.enabled = True
base = aerial.base_of(scene)
foreign = pathlib.Path(scene_export.frame_path(base, "aerial", 2))
foreign.parent.mkdir(parents=True, exist_ok=True)
foreign.write_text("not Welkin's")
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "aerial.blend"))
rc, log = render(T.TMP / "aerial.blend", 3)
print("\n".join(line for line in log.splitlines() if "Welkin" in line))
T.check(rc != 0, f"the -a render exited {rc} with frame 2's aerial perspective not written:\n{log[-3000:]}")
T.check(
    "aerial perspective not written for frame 2" in log and "not replaced" in log,
    f"the log does not say why frame 2 failed:\n{log[-3000:]}",
)
T.check(frames_on_disk(out) == ["f_0001.png"], f"frames on disk: {frames_on_disk(out)}")
T.check(
    pathlib.Path(scene_export.frame_path(base, "aerial", 1)).is_file(), "frame 1's aerial passes are missing"
)
T.check(foreign.read_text() == "not Welkin's", "the foreign file was touched")
print("(b) a frame whose aerial perspective failed after saving: removed, exit non-zero")

# (c) The aerial perspective of frame 3 fails before it renders (its VDB file missing).
foreign.unlink()
missing.rename(missing.with_suffix(".kept"))
volume = C.add_volume(scene, paths[0], sequence=4)
out = T.TMP / "c"
scene.render.filepath = str(out / "f_####")
T.check(not world.welkin.active, "the sky is still on: (c) tests the aerial perspective alone")
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "aerial_vdb.blend"))
rc, log = render(T.TMP / "aerial_vdb.blend", 4)
print("\n".join(line for line in log.splitlines() if "Welkin" in line))
T.check(rc != 0, f"the -a render exited {rc} with frame 3's aerial perspective failing:\n{log[-3000:]}")
T.check(
    "aerial perspective not written for frame 3" in log and missing.name in log,
    f"the log does not say why frame 3 failed:\n{log[-3000:]}",
)
T.check(frames_on_disk(out) == ["f_0001.png", "f_0002.png"], f"frames on disk: {frames_on_disk(out)}")
print("(c) a frame whose aerial perspective failed before rendering: not written")

# (d) The Welkin render engine: its error report fails the frame (Blender's own rule).
scene.welkin_aerial.enabled = False
scene.render.engine = "WELKIN"
out = T.TMP / "d"
scene.render.filepath = str(out / "f_####")
bpy.ops.wm.save_as_mainfile(filepath=str(T.TMP / "engine.blend"))
rc, log = render(T.TMP / "engine.blend", 4)
T.check(rc != 0, f"the Welkin engine's -a render exited {rc} with frame 3 failing:\n{log[-3000:]}")
T.check(missing.name in log, f"the log does not say why frame 3 failed:\n{log[-3000:]}")
T.check(frames_on_disk(out) == ["f_0001.png", "f_0002.png"], f"frames on disk: {frames_on_disk(out)}")
print("(d) the Welkin engine's failed frame: not written, exit non-zero")

T.done("test_addon_farm")
