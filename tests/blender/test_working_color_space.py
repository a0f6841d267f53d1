# SPDX-License-Identifier: Apache-2.0
"""Headless Blender 5.0+: the same scene renders the same in every working colour space.

Blender 5.0 stores a file's colours in its working space (bpy.data.colorspace.working_space:
Linear Rec.709, Linear Rec.2020 or ACEScg). One scene (a synced sun lamp, the Welkin sky,
a grey ground and blocks up to 24 km under Aerial Perspective's haze) is rendered by Cycles
in a Linear Rec.709 file, then switched with Blender's own operator
(wm.set_working_color_space, which converts the file's colours) to Linear Rec.2020 and to
ACEScg, Welkin updated, and rendered again (Aerial Perspective off for the switch:
Blender refuses to switch while an image is modified and unsaved, and its tables, baked
per frame, always are). Each render, in its working space, is taken to
Linear Rec.709 by welkin.color_space_matrix (checked against the published matrices in
tests/cpp/test_color_space.cpp) and compared with the Rec.709 render:
  * the sky (the world image seen by camera rays: no noise) within 0.2 %;
  * the grey ground and blocks, lit by the lamp and the sky, hazed, over 8 x 8 pixel
    blocks (Cycles' noise, whose light sampling follows the lamp's RGB and so differs
    between the files, averaged down): within 1 % on average and 3 % in any block. The
    materials are grey, which every space holds as the same numbers, so what changes
    between the renders is Welkin's colour (lamp, sky, disc, haze tables) and Cycles'
    per-channel products in another basis (Image x T of the haze among them).
    (Measured: docs/validation.md, "Working colour spaces".)
Rec.709 numbers read as ACEScg (what Welkin handed Blender before it knew the working
space) are checked to be far outside these tolerances, so the comparison can fail for
that reason; the synced lamp colour is checked to be the Rec.709 file's in each space.
The Welkin render engine's frame (the core's plate, no noise; its haze, too, multiplies
per channel) is the same within 0.5 % in every pixel.
Finally the ACEScg file, saved and rendered in a fresh process (`blender -b file -f 1`),
gives the same frame as in this process.
"""

import math
import os
import pathlib
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as at  # noqa: E402

if not hasattr(getattr(bpy.data, "colorspace", None), "working_space"):
    at.skip("test_working_color_space", "no working colour space before Blender 5.0")

addon, module = at.install_addon()
from welkin.blender import compat  # noqa: E402
from welkin.blender.sky import update  # noqa: E402

W, H = 96, 48
SPACES = (("Linear Rec.709", "rec709"), ("Linear Rec.2020", "rec2020"), ("ACEScg", "acescg"))


def grey(name, value):
    m = bpy.data.materials.new(name)
    if m.node_tree is None:  # before 5.0 (use_nodes is deprecated from 5.0)
        m.use_nodes = True
    m.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (value, value, value, 1)
    return m


def build_scene():
    scene, sun = at.new_scene(sun_elevation_deg=12.0, sun_azimuth_deg=40.0, camera_z=30.0)
    sun.data.energy = 4.0
    cam = scene.camera
    cam.rotation_euler = (math.radians(86.0), 0.0, math.radians(-90.0))
    cam.data.lens = 30.0
    cam.data.clip_end = 1e6
    bpy.ops.mesh.primitive_plane_add(size=200000.0)
    bpy.context.active_object.data.materials.append(grey("Ground", 0.2))
    for k, d in enumerate((300.0, 3000.0, 12000.0, 24000.0)):
        s = 0.12 * d
        bpy.ops.mesh.primitive_cube_add(size=s, location=(d, (k % 2 - 0.5) * 0.3 * d, 0.5 * s))
        bpy.context.active_object.data.materials.append(grey(f"Block {k}", 0.5))
    scene.world.welkin.preset = "hazy"
    scene.world.welkin.sync_lamp = True
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.resolution_percentage = 100
    scene.cycles.device = "CPU"
    scene.cycles.samples = 8
    scene.cycles.seed = 3
    scene.cycles.use_denoising = False
    scene.view_settings.view_transform = "Standard"
    compat.set_exr(scene.render.image_settings, multilayer=False)
    scene.render.image_settings.color_depth = "32"
    scene.welkin_aerial.enabled = True
    return scene, sun


def render(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return at.read_rgb_exr(module, path)


def engine_frame(scene, path):
    """The same frame from the Welkin render engine (the core's camera plate: sky, lit
    ground, haze; no noise)."""
    scene.render.engine = "WELKIN"
    try:
        return render(scene, path)
    finally:
        scene.render.engine = "CYCLES"


def to_rec709(rgb, space):
    m = np.asarray(module.color_space_matrix(space, "rec709"))
    return rgb @ m.T


def switch(scene, working_space):
    """Blender's operator, as an artist uses it. It refuses while an image is modified and
    unsaved, which Aerial Perspective's tables always are (baked per frame, never saved):
    turned off for the switch and on again, as artists.md says."""
    scene.welkin_aerial.enabled = False
    bpy.ops.wm.save_as_mainfile(filepath=str(at.TMP / "switching.blend"))  # packs the sky
    result = bpy.ops.wm.set_working_color_space(working_space=working_space)
    at.check(
        bpy.data.colorspace.working_space == working_space,
        f"the operator did not switch to {working_space}: {result}",
    )
    scene.welkin_aerial.enabled = True
    update.update_sky(scene)  # what the depsgraph handler does in the interface


def block_means(rgb, mask, n=8):
    """Means of rgb over n x n pixel blocks, counting only `mask`'s pixels (blocks with
    fewer than half of theirs left out): Cycles' noise averaged down."""
    h, w = mask.shape
    out = []
    for y in range(0, h - n + 1, n):
        for x in range(0, w - n + 1, n):
            m = mask[y : y + n, x : x + n]
            if m.sum() >= n * n // 2:
                out.append(rgb[y : y + n, x : x + n][m].mean(axis=0))
    return np.asarray(out)


def compare(name, got, want, sky):
    """(sky's largest relative difference, ground's over 8 x 8 blocks: mean and largest)."""
    s = (np.abs(got - want) / np.maximum(np.abs(want), 1e-4))[sky].max()
    g, w = block_means(got, ~sky), block_means(want, ~sky)
    rel = np.abs(g - w) / np.maximum(np.abs(w), 1e-4)
    p = np.percentile((np.abs(got - want) / np.maximum(np.abs(want), 1e-4))[~sky], [50, 90, 99])
    print(
        f"{name}: sky max {s:.5f}; ground and blocks over {len(g)} blocks of 8 x 8: "
        f"mean {rel.mean():.5f} max {rel.max():.5f} (per pixel: median {p[0]:.4f}, "
        f"90 % {p[1]:.4f}, 99 % {p[2]:.4f})"
    )
    return s, rel.mean(), rel.max()


def main():
    scene, sun = build_scene()
    tmp = at.TMP
    switch(scene, "Linear Rec.709")
    want = render(scene, tmp / "rec709.exr")
    # Sky pixels (the camera ray meets no geometry): where the world alone, every object
    # hidden from the camera, gives the same frame.
    for obj in scene.objects:
        if obj.type == "MESH":
            obj.visible_camera = False
    world_only = render(scene, tmp / "world.exr")
    for obj in scene.objects:
        if obj.type == "MESH":
            obj.visible_camera = True
    sky = np.all(np.abs(world_only - want) <= 1e-6 * np.abs(want) + 1e-9, axis=-1)
    at.check(10 < sky.sum() < sky.size - 10, f"{sky.sum()} sky pixels of {sky.size}: no horizon")
    lamp709 = tuple(sun.data.color)
    plate709 = engine_frame(scene, tmp / "plate_rec709.exr")
    for working, space in SPACES[1:]:
        switch(scene, working)
        got = to_rec709(render(scene, tmp / f"{space}.exr"), space)
        s, mean, worst = compare(space, got, want, sky)
        at.check(s < 0.002, f"{space}: the sky is {s:.4f} from the Rec.709 file's")
        at.check(
            mean < 0.01 and worst < 0.03,
            f"{space}: the ground is {mean:.4f} (mean), {worst:.4f} (worst block) from the Rec.709 file's",
        )
        plate = to_rec709(engine_frame(scene, tmp / f"plate_{space}.exr"), space)
        d = (np.abs(plate - plate709) / np.maximum(np.abs(plate709), 1e-4)).max()
        print(f"{space}: the Welkin engine's frame is {d:.2e} from the Rec.709 file's")
        at.check(d < 0.005, f"{space}: the Welkin engine's frame is {d:.4f} from the Rec.709 file's")
        lamp = np.asarray(sun.data.color)
        m = np.asarray(module.color_space_matrix("rec709", space))
        want_lamp = m @ np.asarray(lamp709)
        at.check(
            np.allclose(lamp / lamp.max(), want_lamp / want_lamp.max(), atol=2e-3),
            f"{space}: lamp colour {lamp} is not the Rec.709 file's {lamp709} in {space}",
        )
    # Rec.709 numbers read as ACEScg (what Welkin gave Blender before): far outside.
    _s, mean, _worst = compare("Rec.709 numbers read as ACEScg", to_rec709(want, "acescg"), want, sky)
    at.check(mean > 0.03, f"relabelling is only {mean:.4f} off: the test cannot tell")
    # The ACEScg file in a fresh process.
    blend = tmp / "acescg.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = tmp / "fresh_"
    cmd = [
        *at.blender_command(),
        "-b",
        "--factory-startup",
        str(blend),
        "--addons",
        "welkin",
        "-o",
        str(out) + "####",
        "-F",
        "OPEN_EXR",
        "-f",
        "1",
    ]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["BLENDER_USER_SCRIPTS"] = str(at.scripts_dir())
    env["BLENDER_USER_CONFIG"] = str(at.TMP / "config")
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=900, env=env)
    at.check(r.returncode == 0, f"-f 1 exited {r.returncode}:\n{r.stdout[-3000:]}\n{r.stderr[-2000:]}")
    fresh = to_rec709(at.read_rgb_exr(module, f"{out}0001.exr"), "acescg")
    s, mean, worst = compare("acescg file, fresh process", fresh, want, sky)
    at.check(s < 0.002 and mean < 0.01 and worst < 0.03, "the saved ACEScg file renders otherwise")
    at.done("test_working_color_space")


main()
