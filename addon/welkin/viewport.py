# SPDX-License-Identifier: GPL-3.0-or-later
"""The viewport preview's camera and schedule, Blender-free (blender/engine/viewport.py
draws it).

A 3D viewport in Rendered shading sees the world through its region's matrices:
`view_matrix` V (world to view: a rotation and a translation; the view looks down its
local -Z with +Y up, as a camera) and `window_matrix` P (view to clip, OpenGL). Blender
builds P from an off-axis frustum [l, r] x [b, t] at the near distance n (perspective,
BKE_camera_params_compute_matrix) or from the box [l, r] x [b, t] (orthographic):

    perspective   P00 = 2n / (r - l)   P02 = (r + l) / (r - l)
                  P11 = 2n / (t - b)   P12 = (t + b) / (t - b)
                  P22 = -(f + n) / (f - n)   P23 = -2 f n / (f - n)   P32 = -1
    orthographic  P00 = 2 / (r - l)    P03 = -(r + l) / (r - l)
                  P11 = 2 / (t - b)    P13 = -(t + b) / (t - b)
                  P22 = -2 / (f - n)   P23 = -(f + n) / (f - n)       P33 = 1

and a Blender camera whose sensor is fitted to the width (sensor_fit HORIZONTAL, sensor
width s, focal length F, shift in units of the width w, square pixels, BKE's viewplane)
has exactly such a frustum: (r - l) / n = s / F, (r + l) / (r - l) = 2 shift_x,
(t + b) / (t - b) = 2 shift_y w / h; orthographic: r - l = ortho_scale, the same shifts.
So the region's view is the camera

    matrix_world = V^-1,  lens = P00 s / 2,  shift_x = P02 / 2,  shift_y = P12 h / (2 w)
    (orthographic: ortho_scale = 2 / P00,  shift_x = -P03 / 2,  shift_y = -P13 h / (2 w))

which the core renders like any scene camera (camera.hpp): the free view, and the camera
view (view_perspective 'CAMERA', where V is the scene camera's inverse and P its frustum
widened to the region, its frame inside), whose pixels in the frame are the scene
camera's. Nothing here is physics: the plate comes from the core (welkin.
CameraPlateRenderer), the add-on only says which camera looks.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

# Any sensor width gives the same frustum (lens scales with it); Blender's default.
SENSOR_WIDTH_MM = 36.0
# The first preview level: 1/8 of the region's size, then 1/4, 1/2, 1.
FIRST_DIVISOR = 8
# Rows per band of a level: a band is what a cancel waits for at most.
BAND_ROWS = 32


def _rigid_inverse(m: list[list[float]]) -> list[list[float]]:
    """The inverse of a 4 x 4 rigid transform (rows): [R t; 0 1]^-1 = [R^T -R^T t; 0 1]."""
    r = [[float(m[j][i]) for j in range(3)] for i in range(3)]  # R^T
    t = [float(m[i][3]) for i in range(3)]
    out = [r[i] + [-sum(r[i][k] * t[k] for k in range(3))] for i in range(3)]
    return out + [[0.0, 0.0, 0.0, 1.0]]


def camera_from_view(
    view_matrix: Iterable[Iterable[float]],
    window_matrix: Iterable[Iterable[float]],
    is_perspective: bool,
    width: int,
    height: int,
    scale_length: float = 1.0,
) -> dict[str, Any]:
    """The scene JSON's "camera" (docs/pipelines.md "Scene JSON") that sees what a viewport region of
    width x height pixels sees, from its view_matrix and window_matrix (4 rows each, in
    scene units; see the module's docstring). ValueError naming the matrix when it is not
    a projection Blender makes."""
    if width < 1 or height < 1:
        raise ValueError(f"region size: must be at least 1 x 1 pixels, got {width} x {height}")
    p = [[float(v) for v in row] for row in window_matrix]
    v = [[float(x) for x in row] for row in view_matrix]
    if not all(math.isfinite(x) for row in p + v for x in row):
        raise ValueError("window_matrix / view_matrix: must be finite")
    if not (p[0][0] > 0.0 and p[1][1] > 0.0):
        raise ValueError(
            f"window_matrix: expected a projection with positive scales, got "
            f"P00 = {p[0][0]:g}, P11 = {p[1][1]:g}"
        )
    s = float(scale_length)
    world = _rigid_inverse(v)
    aspect = height / width
    if is_perspective:
        n = p[2][3] / (p[2][2] - 1.0)
        f = p[2][3] / (p[2][2] + 1.0)
        cam: dict[str, Any] = {
            "type": "PERSP",
            "lens_mm": p[0][0] * SENSOR_WIDTH_MM / 2.0,
            "ortho_scale": 1.0,
            "shift_x": p[0][2] / 2.0,
            "shift_y": p[1][2] * aspect / 2.0,
        }
    else:
        # Blender's viewport clips orthographic views from -clip_end / 2 (behind the eye):
        # the rays start on the view's plane (camera.hpp), so only a valid range is kept.
        n = (p[2][3] + 1.0) / p[2][2]
        f = (p[2][3] - 1.0) / p[2][2]
        cam = {
            "type": "ORTHO",
            "lens_mm": 50.0,
            "ortho_scale": 2.0 / p[0][0] * s,
            "shift_x": -p[0][3] / 2.0,
            "shift_y": -p[1][3] * aspect / 2.0,
        }
    n, f = n * s, f * s
    if not (0.0 < n < f):
        n, f = 1e-3, max(f, 1.0)
    for r in range(3):
        world[r][3] *= s
    cam.update(
        {
            "matrix_world": world,
            "sensor_width_mm": SENSOR_WIDTH_MM,
            "sensor_height_mm": SENSOR_WIDTH_MM * aspect,
            "sensor_fit": "HORIZONTAL",
            "clip_start_m": n,
            "clip_end_m": f,
        }
    )
    return cam


def levels(width: int, height: int, first_divisor: int = FIRST_DIVISOR) -> list[tuple[int, int]]:
    """The preview's resolutions for a region of width x height: 1/first_divisor of it,
    then each twice the last, up to the region's own (ceil, at least 1 x 1)."""
    out: list[tuple[int, int]] = []
    d = first_divisor
    while True:
        size = (max(1, -(-width // d)), max(1, -(-height // d)))
        if not out or size != out[-1]:
            out.append(size)
        if d == 1:
            return out
        d = max(1, d // 2)


def drawn_size(region_width: int, level_width: int, level_height: int) -> tuple[int, float]:
    """The size a level's image is drawn at over its region: its width is the region's and
    its height keeps the level's aspect (the camera is fitted to the width), so a level
    whose rounded height differs from the region's by a fraction of its pixel is not
    stretched."""
    return region_width, level_height * region_width / level_width
