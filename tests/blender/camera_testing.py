# SPDX-License-Identifier: Apache-2.0
"""The scene JSON's camera, written from bpy data as docs/pipelines.md "Scene JSON" says the add-on
writes it. Tests of the camera convention build it here, independently of the add-on's
own export, so that the core is checked against Blender itself."""

import math


def camera_json(ob):
    cam = ob.data
    d = {
        "matrix_world": [list(r) for r in ob.matrix_world],
        "type": cam.type,
        "lens_mm": cam.lens,
        "sensor_width_mm": cam.sensor_width,
        "sensor_height_mm": cam.sensor_height,
        "sensor_fit": cam.sensor_fit,
        "ortho_scale": cam.ortho_scale,
        "shift_x": cam.shift_x,
        "shift_y": cam.shift_y,
        "clip_start_m": cam.clip_start,
        "clip_end_m": cam.clip_end,
    }
    if cam.type == "PANO":
        # On the camera from 4.0, on Cycles' camera settings in 3.x (as compat.camera_panorama;
        # not imported here, so that tests without the add-on can use this).
        c = cam if hasattr(cam, "panorama_type") else cam.cycles
        d.update(
            panorama_type=c.panorama_type,
            latitude_min_deg=math.degrees(c.latitude_min),
            latitude_max_deg=math.degrees(c.latitude_max),
            longitude_min_deg=math.degrees(c.longitude_min),
            longitude_max_deg=math.degrees(c.longitude_max),
        )
    return d
