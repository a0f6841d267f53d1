# SPDX-License-Identifier: Apache-2.0
"""The viewport preview's camera (addon/welkin/viewport.py): a viewport's view_matrix and
window_matrix become a scene camera whose rays, through the core (SceneDescription.
camera_ray), are the closed-form rays of the frustum: perspective, the ray through the
near-plane point (l + sx (r - l), t - sy (t - b), -n) from the eye; orthographic, the
view axis from the point (l + sx (r - l), t - sy (t - b), 0) of the view's plane; both
turned by the view's rotation. Off-axis frusta (lens shift, Blender's camera view) too.
The preview's levels and drawn size."""

import json
import math

import numpy as np
import pytest

import welkin

from welkin_addon import viewport


def rotation(yaw, pitch, roll):
    """A camera-to-world rotation: Z-up world, the view first looking down -Z, then
    tilted to the horizon (pitch), turned about Z (yaw) and rolled."""

    def rx(a):
        c, s = math.cos(a), math.sin(a)
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])

    def rz(a):
        c, s = math.cos(a), math.sin(a)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])

    return rz(yaw) @ rx(pitch) @ rz(roll)


def view_matrix(rot, eye):
    v = np.eye(4)
    v[:3, :3] = rot.T
    v[:3, 3] = -rot.T @ eye
    return v


def perspective(l, r, b, t, n, f):
    p = np.zeros((4, 4))
    p[0, 0], p[0, 2] = 2 * n / (r - l), (r + l) / (r - l)
    p[1, 1], p[1, 2] = 2 * n / (t - b), (t + b) / (t - b)
    p[2, 2], p[2, 3] = -(f + n) / (f - n), -2 * f * n / (f - n)
    p[3, 2] = -1
    return p


def orthographic(l, r, b, t, n, f):
    p = np.eye(4)
    p[0, 0], p[0, 3] = 2 / (r - l), -(r + l) / (r - l)
    p[1, 1], p[1, 3] = 2 / (t - b), -(t + b) / (t - b)
    p[2, 2], p[2, 3] = -2 / (f - n), -(f + n) / (f - n)
    return p


def scene_for(camera, w, h):
    return welkin.SceneDescription.from_json_string(
        json.dumps(
            {
                "version": 1,
                "atmosphere": "bruneton2017",
                "sun": {"elevation_deg": 20, "azimuth_deg": 0},
                "camera": camera,
                "resolution": {"x": w, "y": h, "percentage": 100},
            }
        )
    )


SCREEN = [(0.5, 0.5), (0.0, 0.0), (1.0, 1.0), (0.1, 0.9), (0.77, 0.31)]


@pytest.mark.parametrize(
    "w,h,frustum",
    [
        (160, 90, (-0.6, 0.6, -0.3375, 0.3375)),  # centred, 16:9
        (90, 160, (-0.2, 0.5, -0.4, 0.844)),  # off-axis, portrait (a camera view)
        (101, 77, (-1.3, 0.2, -0.5, 0.6431683)),  # odd size, wide off-axis
    ],
)
def test_perspective_rays_closed_form(w, h, frustum):
    l, r, b, t = frustum
    t = b + (r - l) * h / w  # square pixels: the region's aspect
    n, f = 0.05, 800.0
    rot, eye = rotation(0.7, 1.4, 0.1), np.array([3.0, -2.0, 12.0])
    cam = viewport.camera_from_view(
        view_matrix(rot, eye), perspective(l * n, r * n, b * n, t * n, n, f), True, w, h
    )
    assert cam["type"] == "PERSP" and cam["clip_start_m"] == pytest.approx(n)
    assert cam["clip_end_m"] == pytest.approx(f)
    s = scene_for(cam, w, h)
    for sx, sy in SCREEN:
        origin, direction, _ = s.camera_ray(sx, sy)
        local = np.array([l + sx * (r - l), t - sy * (t - b), -1.0])
        expected = rot @ local / np.linalg.norm(local)
        np.testing.assert_allclose(origin, eye, atol=1e-9)
        np.testing.assert_allclose(direction, expected, atol=1e-9)


def test_orthographic_rays_closed_form():
    w, h = 120, 80
    l, r, b = -7.0, 5.0, -3.0
    t = b + (r - l) * h / w
    rot, eye = rotation(-0.4, 0.9, 0.0), np.array([1.0, 2.0, 40.0])
    # Blender's viewport clips orthographic views from behind the eye (-clip_end / 2).
    cam = viewport.camera_from_view(
        view_matrix(rot, eye), orthographic(l, r, b, t, -500.0, 500.0), False, w, h
    )
    assert cam["type"] == "ORTHO" and cam["ortho_scale"] == pytest.approx(r - l)
    assert 0 < cam["clip_start_m"] < cam["clip_end_m"]
    s = scene_for(cam, w, h)
    for sx, sy in SCREEN:
        origin, direction, _ = s.camera_ray(sx, sy)
        np.testing.assert_allclose(direction, rot @ np.array([0, 0, -1.0]), atol=1e-12)
        np.testing.assert_allclose(
            origin, eye + rot @ np.array([l + sx * (r - l), t - sy * (t - b), 0]), atol=1e-9
        )


def test_scale_length_and_bad_matrices():
    rot, eye = rotation(0.0, 1.2, 0.0), np.array([1.0, 2.0, 3.0])
    p = perspective(-0.05, 0.05, -0.03, 0.03, 0.05, 100.0)
    cam = viewport.camera_from_view(view_matrix(rot, eye), p, True, 100, 60, scale_length=0.01)
    np.testing.assert_allclose([row[3] for row in cam["matrix_world"][:3]], eye * 0.01)
    assert cam["clip_start_m"] == pytest.approx(0.05 * 0.01)
    with pytest.raises(ValueError, match="window_matrix"):
        viewport.camera_from_view(view_matrix(rot, eye), np.zeros((4, 4)), True, 100, 60)
    with pytest.raises(ValueError, match="region size"):
        viewport.camera_from_view(view_matrix(rot, eye), p, True, 0, 60)
    bad = p.copy()
    bad[0, 0] = math.nan
    with pytest.raises(ValueError, match="finite"):
        viewport.camera_from_view(view_matrix(rot, eye), bad, True, 100, 60)


def test_levels_and_drawn_size():
    assert viewport.levels(1000, 600) == [(125, 75), (250, 150), (500, 300), (1000, 600)]
    assert viewport.levels(9, 5) == [(2, 1), (3, 2), (5, 3), (9, 5)]
    assert viewport.levels(1, 1) == [(1, 1)]
    # A level keeps its aspect when drawn over the region's width.
    assert viewport.drawn_size(9, 2, 1) == (9, 4.5)
