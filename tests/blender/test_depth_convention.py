# SPDX-License-Identifier: Apache-2.0
"""Headless Blender + Cycles: Welkin reads Blender's Z pass as Blender writes it.

A small scene (a ground plane and a wall standing on one side only, so that a mirrored
image would be caught) is rendered by Cycles with the Z pass into a multilayer EXR, for a
perspective camera (sensor fit, shift), an orthographic one and an equirectangular
panorama. For every pixel whose ray hits the ground or the wall, the depth Cycles wrote must
equal what Welkin's camera model says: the distance to the hit along Welkin's ray for that
pixel, divided by distance_per_depth (the view-axis depth for perspective and orthographic
cameras, the distance along the ray for panoramas), within 0.5 % (pixel filtering blurs
depth across edges; pixels next to an edge are left out; the wall must be among the
pixels compared). The EXR is read back with
welkin.read_exr, and the channel is the one `welkin aerial` finds by default
("ViewLayer.Depth.Z").

Run: bash scripts/test_blender.sh tests/blender/test_depth_convention.py
"""

import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

import bpy
from mathutils import Euler

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing  # noqa: E402
from camera_testing import camera_json  # noqa: E402

# The compiled core as the installed add-on carries it (legacy zip or Extension's wheel).
_addon, welkin = addon_testing.install_addon()
from welkin.blender import compat  # noqa: E402

CLI = os.environ.get("WELKIN_CLI", str(pathlib.Path(__file__).resolve().parents[2] / "build" / "welkin"))
WALL_Y = 30.0  # the wall's plane, y = WALL_Y, for |x| < 40, 0 < z < 25


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "GAUSSIAN"  # a box is one pixel wide whatever its width
    scene.cycles.filter_width = 0.01  # point samples at the pixel centres
    scene.render.film_transparent = False
    scene.view_layers[0].use_pass_z = True
    bpy.ops.mesh.primitive_plane_add(size=400.0, location=(0, 0, 0))
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0, WALL_Y, 12.5), rotation=(math.radians(90), 0, 0))
    wall = bpy.context.active_object
    wall.scale = (80.0, 25.0, 1.0)
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    return scene, cam


def expected_distance(o, d):
    """Distance along the ray to the ground (z = 0, |x|, |y| < 200) or the wall, and
    whether the wall is the hit."""
    best, wall = math.inf, False
    if d[2] < -1e-9:
        t = -o[2] / d[2]
        x, y = o[0] + t * d[0], o[1] + t * d[1]
        if abs(x) < 200 and abs(y) < 200:
            best = t
    if abs(d[1]) > 1e-9:
        t = (WALL_Y - o[1]) / d[1]
        x, z = o[0] + t * d[0], o[2] + t * d[2]
        if t > 0 and abs(x) < 40 and 0 < z < 25 and t < best:
            best, wall = t, True
    return best, wall


def check(scene, cam, label, tmp):
    r = scene.render
    path = os.path.join(tmp, f"{label}.exr")
    compat.set_file_format(r.image_settings, "OPEN_EXR_MULTILAYER")
    r.filepath = path
    bpy.ops.render.render(write_still=True)
    pixels, names = welkin.read_exr(path)
    z = pixels[..., names.index("ViewLayer.Depth.Z")]
    desc = welkin.SceneDescription.from_json_string(
        json.dumps(
            {
                "version": 1,
                "camera": camera_json(cam),
                "resolution": {
                    "x": r.resolution_x,
                    "y": r.resolution_y,
                    "percentage": r.resolution_percentage,
                },
            }
        )
    )
    H, W = z.shape
    assert (W, H) == (desc.width, desc.height), (W, H, desc.width, desc.height)
    expect = np.full((H, W), np.inf)
    on_wall = np.zeros((H, W), bool)
    for j in range(H):
        for i in range(W):
            o, d, k = desc.camera_ray((i + 0.5) / W, (j + 0.5) / H)
            t, on_wall[j, i] = expected_distance(o, d)
            expect[j, i] = t / k
    # Leave out pixels next to an edge (where the neighbours' depths differ by > 2 %).
    finite = np.isfinite(expect)
    pad = np.pad(np.where(finite, expect, 1e30), 1, mode="edge")
    smooth = np.ones_like(finite)
    for dj in (-1, 0, 1):
        for di in (-1, 0, 1):
            nb = pad[1 + dj : 1 + dj + H, 1 + di : 1 + di + W]
            smooth &= np.abs(nb - np.where(finite, expect, 1e30)) <= 0.02 * np.abs(nb)
    use = finite & smooth
    assert use.sum() > 0.05 * W * H, f"{label}: too few pixels to compare ({use.sum()})"
    # The wall stands on one side only: a mirrored or turned image fails on it.
    assert (use & on_wall).sum() > 20, f"{label}: the wall is not in view ({(use & on_wall).sum()})"
    rel = np.abs(z[use] - expect[use]) / expect[use]
    assert rel.max() < 5e-3, f"{label}: Z pass vs Welkin's camera: worst {rel.max():.4f}"
    # Background pixels: Cycles writes a huge depth, which Welkin takes as sky.
    sky = ~finite & smooth
    if sky.any():
        assert (z[sky] >= 1e9).all(), f"{label}: background depth {z[sky].min()}"
    print(
        f"ok: {label}: {use.sum()} pixels ({(use & on_wall).sum()} on the wall), "
        f"worst {100 * rel.max():.3f} %"
    )
    return path, z, use


def aerial_from_cycles_render(scene, cam, path, z, use, tmp):
    """`welkin aerial` on Cycles' own multilayer EXR: it finds ViewLayer.Depth.Z, and the
    passes get hazier with depth (the nearest compared pixels against the farthest)."""
    r = scene.render
    frame = os.path.join(tmp, "frame.json")
    with open(frame, "w") as f:
        json.dump(
            {
                "version": 1,
                "atmosphere": "hazy",
                "camera": camera_json(cam),
                "sun": {"elevation_deg": 20, "azimuth_deg": 40},
                "resolution": {
                    "x": r.resolution_x,
                    "y": r.resolution_y,
                    "percentage": r.resolution_percentage,
                },
            },
            f,
        )
    out = os.path.join(tmp, "passes.exr")
    run = subprocess.run(
        [CLI, "aerial", "--scene", frame, "--depth", path, "-o", out],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    pixels, names = welkin.read_exr(out)
    T = pixels[..., names.index("Welkin.AerialTransmittance.G")]
    L = pixels[..., names.index("Welkin.AerialInscatter.G")]
    zz = np.where(use, z, np.nan)
    near, far = np.nanargmin(zz), np.nanargmax(zz)
    assert T.flat[far] < T.flat[near] and L.flat[far] > L.flat[near], (z.flat[near], z.flat[far])
    sky = z >= 1e9
    assert (T[sky] == 1).all() and (L[sky] == 0).all()
    print(
        f"ok: welkin aerial on the Cycles render: T {T.flat[near]:.4f} at {z.flat[near]:.1f} m, "
        f"{T.flat[far]:.4f} at {z.flat[far]:.1f} m"
    )


def main():
    scene, cam = build_scene()
    scene.render.resolution_x, scene.render.resolution_y = 96, 64
    scene.render.resolution_percentage = 100
    cam.location = (-8.0, -20.0, 6.0)
    cam.rotation_euler = Euler((math.radians(80), 0, math.radians(-20)))
    cam.data.lens = 30.0
    cam.data.shift_x, cam.data.shift_y = 0.1, -0.05
    with tempfile.TemporaryDirectory() as tmp:
        path, z, use = check(scene, cam, "perspective", tmp)
        aerial_from_cycles_render(scene, cam, path, z, use, tmp)
        cam.data.sensor_fit = "VERTICAL"
        scene.render.resolution_x, scene.render.resolution_y = 64, 96
        check(scene, cam, "perspective_portrait_vertical", tmp)
        cam.data.type = "ORTHO"
        cam.data.ortho_scale = 30.0
        cam.data.shift_x = cam.data.shift_y = 0.0
        cam.location = (-5.0, 8.0, 20.0)
        cam.rotation_euler = Euler((math.radians(50), 0, math.radians(-20)))
        check(scene, cam, "orthographic", tmp)
        cam.data.type = "PANO"
        compat.camera_panorama(cam.data).panorama_type = "EQUIRECTANGULAR"
        cam.location = (5.0, 0.0, 4.0)
        cam.rotation_euler = Euler((math.radians(90), 0, math.radians(-90)))
        scene.render.resolution_x, scene.render.resolution_y = 128, 64
        check(scene, cam, "panorama", tmp)
        cam.rotation_euler = Euler((math.radians(70), math.radians(10), math.radians(30)))
        check(scene, cam, "panorama_turned", tmp)
    print("test_depth_convention: all passed")


main()
