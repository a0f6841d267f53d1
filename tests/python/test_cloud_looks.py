# SPDX-License-Identifier: Apache-2.0
"""What the cloud types look like, measured on their density (clouds/procedural.hpp).

The WMO International Cloud Atlas describes cumulus with nearly level bases under domed,
bulging tops, and cirrus as filaments: two properties of the shape that a number can say.

* Flat bases, domed tops (cumulus, and the other cell types): over a square of columns, each
  cloud column (vertical optical depth at least 2: the cloud's body, not its thin edge) has
  its base where the density first reaches half the layer's largest, and its top where it
  last does. The spread of the bases (10th to 90th percentile) stays under 5 % of the
  layer's thickness, the spread of the tops over 10 %: a flat underside and heaps of
  different heights over it, where a slab or a 3D noise blob fails one or the other.
* Fibres (cirrus): the autocorrelation of the map of the vertical optical depth seen from
  above falls to a quarter at a lag along the streaks (30 degrees off x) at least three
  times the lag across them; the cells of cumulus are round (the same ratio under 1.6).
  (A quarter, not a half: the fibres, finer than the map's pixels, decorrelate the first
  pixel in every direction.)
"""

import json
import math

import numpy as np
import pytest

import welkin
from test_cloud_tiling import autocorrelation

R_PLANET = 6360e3
STREAK = math.radians(30.0)


def density_columns(layer, span_m, n, steps):
    """sigma_t at `steps` heights (midpoints) of n x n columns over a square `span_m` wide about
    the origin, each along the local vertical of the curved shell; and the heights above the
    layer's bottom."""
    xs = (np.arange(n) + 0.5 - n / 2) * span_m / n
    x, y = np.meshgrid(xs, xs, indexing="xy")
    up = np.stack([x, y, np.full_like(x, R_PLANET)], -1)
    up /= np.linalg.norm(up, axis=-1, keepdims=True)
    bottom, top = layer.bottom_altitude_m, layer.top_altitude_m
    dh = (top - bottom) / steps
    heights = (np.arange(steps) + 0.5) * dh
    sigma = np.empty((n, n, steps))
    for k, h in enumerate(heights):
        p = up * (R_PLANET + bottom + h)
        p[..., 2] -= R_PLANET
        sigma[..., k] = layer.sigma_t(p.reshape(-1, 3)).reshape(x.shape)
    return sigma, heights, dh


@pytest.mark.parametrize("cloud_type", ["cumulus", "stratocumulus", "altocumulus"])
def test_cells_have_flat_bases_under_tops_of_many_heights(cloud_type):
    preset = welkin.cloud_type_preset(cloud_type)
    layer = welkin.CloudLayer(cloud_type=cloud_type)
    thickness = preset["top_altitude_m"] - preset["bottom_altitude_m"]
    sigma, heights, dh = density_columns(layer, 12.0 * preset["base_scale_m"], 96, 160)
    tau = sigma.sum(axis=-1) * dh
    body = tau >= 2.0
    assert body.sum() >= 100, f"only {body.sum()} cloud columns"
    dense = sigma >= 0.5 * preset["density_per_m"]
    first = np.argmax(dense, axis=-1)
    last = dense.shape[-1] - 1 - np.argmax(dense[..., ::-1], axis=-1)
    bases, tops = heights[first[body]], heights[last[body]]
    base_spread = np.percentile(bases, 90) - np.percentile(bases, 10)
    top_spread = np.percentile(tops, 90) - np.percentile(tops, 10)
    print(
        f"{cloud_type}: {body.sum()} columns, base spread {base_spread:.0f} m, top spread "
        f"{top_spread:.0f} m of {thickness:.0f} m"
    )
    assert base_spread < 0.05 * thickness
    assert top_spread > 0.1 * thickness


def quarter_lag(c, pixel_m, angle, level=0.25):
    """The lag (m) along `angle` at which the autocorrelation c (lag 0 at its centre) first
    falls to `level`, by bilinear reads along the ray, linear between the reads."""
    n = c.shape[0] // 2
    prev_r, prev_v = 0.0, 1.0
    for step in range(1, n):
        r = 0.5 * step
        fx, fy = n + r * math.cos(angle), n + r * math.sin(angle)
        i, j = int(fy), int(fx)
        ty, tx = fy - i, fx - j
        v = (
            c[i, j] * (1 - tx) * (1 - ty)
            + c[i, j + 1] * tx * (1 - ty)
            + c[i + 1, j] * (1 - tx) * ty
            + c[i + 1, j + 1] * tx * ty
        )
        if v <= level:
            return (prev_r + (prev_v - level) / (prev_v - v) * (r - prev_r)) * pixel_m
        prev_r, prev_v = r, v
    return n * pixel_m


@pytest.mark.parametrize("cloud_type,lo,hi", [("cirrus", 3.0, math.inf), ("cumulus", 0.0, 1.6)])
def test_cirrus_is_fibrous_and_cumulus_round(cloud_type, lo, hi):
    preset = welkin.cloud_type_preset(cloud_type)
    layer = welkin.CloudLayer(cloud_type=cloud_type)
    span = 6.0 * preset["base_scale_m"]
    n = 256
    sigma, _, dh = density_columns(layer, span, n, 12)
    c = autocorrelation(sigma.sum(axis=-1) * dh)
    along = quarter_lag(c, span / n, STREAK)
    across = quarter_lag(c, span / n, STREAK + math.pi / 2)
    ratio = along / across
    print(
        f"{cloud_type}: quarter-correlation lag {along:.0f} m along the streaks, {across:.0f} m across: {ratio:.2f}"
    )
    assert lo <= ratio <= hi


def box_blur(image, k):
    """The k x k box mean (k odd) of a 2-D array, edges clamped."""
    r = k // 2
    padded = np.pad(image, r, mode="edge")
    c = np.cumsum(np.cumsum(np.pad(padded, ((1, 0), (1, 0))), 0), 1)
    h, w = image.shape
    return (c[k : k + h, k : k + w] - c[:h, k : k + w] - c[k : k + h, :w] + c[:h, :w]) / (k * k)


def test_an_overcast_deck_from_below_has_no_streaks():
    """An overcast stratus seen from the ground (the contact sheet's noon view: sun 60 degrees
    up, 60 degrees right of the view, camera 15 degrees up) is an even grey: the fine
    structure of its luminance, the standard deviation of the image less its 9-pixel box mean
    over the sky's part, relative to the mean, stays under 0.004. Shadow grids turned to the
    sun whose lines cut the deck's flat base at a slant drew streaks along the sun's azimuth
    there (0.0070); the grids of world axes read 0.0025."""
    elevation, azimuth = math.radians(60.0), math.radians(60.0)
    turn = math.radians(90.0 + 15.0)
    scene = {
        "version": 1,
        "atmosphere": "bruneton2017",
        "sun": {
            "direction": [
                math.cos(elevation) * math.sin(azimuth),
                math.cos(elevation) * math.cos(azimuth),
                math.sin(elevation),
            ]
        },
        "camera": {  # Blender's camera (-Z forward, +Y up) turned to look 15 degrees up towards +Y
            "matrix_world": [
                [1, 0, 0, 0],
                [0, math.cos(turn), -math.sin(turn), 0],
                [0, math.sin(turn), math.cos(turn), 20.0],
                [0, 0, 0, 1],
            ],
            "type": "PERSP",
            "fov_deg": 70.0,
            "sensor_width_mm": 36,
            "sensor_height_mm": 24,
        },
        "resolution": {"x": 480, "y": 270, "percentage": 100},
        "clouds": {"layers": [{"cloud_type": "stratus", "coverage": 1.0}], "lighting": {"max_steps": 96}},
    }
    rgb = np.asarray(welkin.camera_plate(json.dumps(scene))["combined"], np.float64)[..., :3]
    y = rgb @ np.array([0.2126, 0.7152, 0.0722])
    sky = y[:200]
    fine = float(np.std(sky - box_blur(sky, 9)) / sky.mean())
    print(f"overcast stratus from below: fine structure {fine:.4f} of the mean")
    assert np.isfinite(sky).all() and sky.min() > 0.0
    assert fine < 0.004
