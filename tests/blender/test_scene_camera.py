# SPDX-License-Identifier: Apache-2.0
"""Headless Blender: the scene description's camera is Blender's camera.

For cameras of every supported kind (perspective with each sensor fit, portrait and
landscape renders, lens shift, field of view; orthographic), the scene JSON is written from
bpy data exactly as docs/pipelines.md "Scene JSON" says the add-on writes it, and the rays Welkin's
core computes through the image corners must pass through the corners of Blender's own
view frame (Camera.view_frame, which applies sensor fit, aspect and shift), to 2e-5 (mathutils is float32). An
equirectangular panorama pointed along +X must look where Blender's Environment Texture
mapping puts each pixel. The sun lamp's direction is its local +Z.

Run: PYTHONPATH=build blender -b --factory-startup --python-use-system-env
     --python-exit-code 1 --python tests/blender/test_scene_camera.py
"""

import json
import math
import pathlib
import sys

import bpy
from mathutils import Euler, Vector

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import addon_testing as T  # noqa: E402
from camera_testing import camera_json  # noqa: E402

# The compiled module as the installed add-on carries it (the legacy zip's, or the
# Extension's wheel on 4.2+).
_addon, welkin = T.install_addon()
from welkin.blender import compat  # noqa: E402


def scene_json(ob, scene, sun_ob):
    r = scene.render
    return json.dumps(
        {
            "version": 1,
            "camera": camera_json(ob),
            "sun": {"direction": list(sun_ob.matrix_world.to_3x3().col[2])},
            "resolution": {"x": r.resolution_x, "y": r.resolution_y, "percentage": r.resolution_percentage},
        }
    )


def close(a, b, tol=2e-5):  # mathutils works in float32
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def check_corners(ob, scene, sun_ob, label):
    desc = welkin.SceneDescription.from_json_string(scene_json(ob, scene, sun_ob))
    cam = ob.data
    frame = [ob.matrix_world @ v for v in cam.view_frame(scene=scene)]
    origin = ob.matrix_world.translation
    welkin_corners = []
    for sx, sy in ((0, 0), (1, 0), (0, 1), (1, 1)):
        o, d, _ = desc.camera_ray(sx, sy)
        welkin_corners.append((Vector(o), Vector(d)))
    for wo, wd in welkin_corners:
        if cam.type == "ORTHO":
            # The ray starts on the camera plane and runs along the view axis: some corner
            # of Blender's frame lies on it.
            ok = any((f - wo).cross(Vector(wd)).length < 1e-4 for f in frame)
        else:
            ok = any(close((f - origin).normalized(), wd) for f in frame)
        assert ok, f"{label}: Welkin's corner ray {tuple(wo)} {tuple(wd)} misses Blender's frame {frame}"
    print(f"ok: {label}")


def main():
    scene = bpy.context.scene
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    cam_data = bpy.data.cameras.new("cam")
    ob = bpy.data.objects.new("cam", cam_data)
    scene.collection.objects.link(ob)
    sun_data = bpy.data.lights.new("sun", "SUN")
    sun_ob = bpy.data.objects.new("sun", sun_data)
    scene.collection.objects.link(sun_ob)
    sun_ob.rotation_euler = Euler((math.radians(60), 0, math.radians(30)))
    ob.location = (12.0, -40.0, 150.0)
    ob.rotation_euler = Euler((math.radians(85), math.radians(3), math.radians(-100)))
    bpy.context.view_layer.update()

    cases = []
    for x, y in ((1920, 1080), (1080, 1920), (1000, 1000)):
        for fit in ("AUTO", "HORIZONTAL", "VERTICAL"):
            for shift in ((0.0, 0.0), (0.2, -0.1)):
                cases.append(dict(type="PERSP", x=x, y=y, fit=fit, shift=shift, lens=35.0))
    cases.append(
        dict(type="PERSP", x=640, y=480, fit="AUTO", shift=(0, 0), lens=None, angle=math.radians(70))
    )
    for fit in ("AUTO", "VERTICAL"):
        cases.append(dict(type="ORTHO", x=800, y=600, fit=fit, shift=(0.1, 0.05), lens=50.0))
    for c in cases:
        scene.render.resolution_x, scene.render.resolution_y = c["x"], c["y"]
        scene.render.resolution_percentage = 50
        cam_data.type = c["type"]
        cam_data.sensor_fit = c["fit"]
        cam_data.sensor_width, cam_data.sensor_height = 36.0, 24.0
        cam_data.shift_x, cam_data.shift_y = c["shift"]
        cam_data.ortho_scale = 17.0
        if c.get("angle"):
            cam_data.angle = c["angle"]  # Blender turns it into lens_mm
        else:
            cam_data.lens = c["lens"]
        bpy.context.view_layer.update()
        check_corners(ob, scene, sun_ob, f"{c['type']} {c['x']}x{c['y']} {c['fit']} shift {c['shift']}")

    # The sun: local +Z of the lamp, a unit vector.
    desc = welkin.SceneDescription.from_json_string(scene_json(ob, scene, sun_ob))
    sun = json.loads(desc.to_json_string())["sun"]["direction"]
    expect = sun_ob.matrix_world.to_3x3() @ Vector((0, 0, 1))
    assert close(sun, expect.normalized(), 1e-6), (sun, expect)
    assert math.isclose(math.degrees(math.asin(sun[2])), 30.0, abs_tol=1e-4)  # 60 deg from zenith

    # Equirectangular panorama pointed along +X (rotation 90, 0, -90): the pixel at
    # (u, 1 - v) looks along Blender's Environment Texture direction of (u, v).
    cam_data.type = "PANO"
    compat.camera_panorama(cam_data).panorama_type = "EQUIRECTANGULAR"
    ob.rotation_euler = Euler((math.radians(90), 0, math.radians(-90)))
    scene.render.resolution_x, scene.render.resolution_y = 200, 100
    bpy.context.view_layer.update()
    desc = welkin.SceneDescription.from_json_string(scene_json(ob, scene, sun_ob))
    for u in (0.1, 0.3, 0.5, 0.8):
        for v in (0.2, 0.5, 0.9):
            _, d, _ = desc.camera_ray(u, 1.0 - v)
            expect = welkin.equirect_to_direction([[u, v]])[0]
            assert close(d, expect, 1e-5), (u, v, d, expect)
    print("ok: panorama")
    print("test_scene_camera: all passed")


main()
