# SPDX-License-Identifier: Apache-2.0
"""The add-on's Blender-free scene export (addon/welkin/scene_export.py): file paths beside
a render, the camera in metres under a scene unit scale, and a scene dict the core accepts
whose camera rays scale with the unit scale."""

import json

import numpy as np

import welkin

from welkin_addon import scene_export


def test_paths_beside_the_render():
    assert scene_export.file_base("/r/out/frame_") == "/r/out/frame_"
    assert scene_export.file_base("/r/out/shot") == "/r/out/shot_"
    assert scene_export.file_base("/r/out/shot_####.exr") == "/r/out/shot_"
    assert scene_export.file_base("/r/out/") == "/r/out/"
    assert scene_export.frame_path("/r/out/shot_", "aerial", 7) == "/r/out/shot_welkin_aerial_0007.exr"
    assert scene_export.frame_path("/r/x_", "scene", 12345) == "/r/x_welkin_scene_12345.json"
    # Blender's File Output node appends the 4-digit frame to its base path.
    assert scene_export.file_output_base("/r/x_") + "0007.exr" == scene_export.frame_path(
        "/r/x_", "render", 7
    )


def _camera(scale):
    m = [[1, 0, 0, 10], [0, 0, -1, -20], [0, 1, 0, 30], [0, 0, 0, 1]]
    return scene_export.camera_dict(m, "ORTHO", 50, 36, 24, "AUTO", 6, 0.1, 0, 0.1, 100, scale_length=scale)


def test_camera_in_metres():
    c = _camera(0.01)
    assert [row[3] for row in c["matrix_world"][:3]] == [0.1, -0.2, 0.3]
    assert c["matrix_world"][0][:3] == [1.0, 0.0, 0.0]  # rotation untouched
    assert np.isclose(c["ortho_scale"], 0.06) and np.isclose(c["clip_end_m"], 1.0)
    assert c["lens_mm"] == 50.0 and c["shift_x"] == 0.1  # not lengths in scene units


def test_scene_dict_is_accepted_and_scales_the_rays():
    rays = []
    for scale in (1.0, 0.01):
        d = scene_export.scene_dict(
            "hazy",
            100.0,
            (0, 0.5, 0.8),
            1.0,
            "lut",
            _camera(scale),
            (64, 32, 100),
            aerial={"method": "froxel"},
        )
        desc = welkin.SceneDescription.from_json_string(json.dumps(d))
        assert (desc.width, desc.height) == (64, 32)
        rays.append(desc.camera_ray(0.0, 0.0))
    (o1, d1, _), (o2, d2, _) = rays
    np.testing.assert_allclose(np.asarray(o2), np.asarray(o1) * 0.01, rtol=1e-12)
    np.testing.assert_allclose(d2, d1, atol=1e-12)


def test_composite():
    image = np.full((2, 2, 3), 2.0, np.float32)
    t = np.full((2, 2, 3), 0.25, np.float32)
    i = np.full((2, 2, 3), 0.5, np.float32)
    np.testing.assert_array_equal(scene_export.composite(image, i, t), np.full((2, 2, 3), 1.0))
