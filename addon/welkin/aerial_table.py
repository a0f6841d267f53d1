# SPDX-License-Identifier: GPL-3.0-or-later
"""The aerial-perspective table as the image the add-on's material node group samples
(bpy-free, so pytest checks it against the core).

welkin.aerial_table() (include/welkin/aerial/aerial_table.hpp) gives, for the frame's camera
position and sun, in-scattering L and optical depth tau per (distance slice k, elevation
row j, azimuth column i). The image packs them as one float RGBA atlas, AZIMUTHS wide and
2 x ELEVATIONS x SLICES tall, rows counted from the bottom (Blender's order):
    row = q * ELEVATIONS * SLICES + k * ELEVATIONS + j,   q = 0: L (RGB), q = 1: tau (RGB)
so that azimuth runs along the image's width (a repeating texture wraps it exactly) and a
tile of ELEVATIONS rows is one distance slice. lookup() reads it the way the node group does
(texel centres, bilinear, the two slices around the distance mixed linearly in distance);
the shader's nodes are built from the same formulas (blender/aerial/frame.py).
"""

from __future__ import annotations

import math

import numpy as np

AZIMUTHS, ELEVATIONS, SLICES = 128, 64, 48
LINEAR_DISTANCE_M = 100.0
STEPS_PER_SLICE = 4
WIDTH, HEIGHT = AZIMUTHS, 2 * ELEVATIONS * SLICES


def max_distance_m(clip_end_m: float, bottom_radius_m: float, top_radius_m: float) -> float:
    """The last slice's distance: the camera's clip end, and no more than the longest path
    through the air above the ground (two tangent rays from the ground to the top)."""
    air = 2.0 * math.sqrt(max(top_radius_m**2 - bottom_radius_m**2, 1.0))
    return float(max(min(clip_end_m, air), 1.0))


def atlas_pixels(inscatter: np.ndarray, optical_depth: np.ndarray) -> np.ndarray:
    """(HEIGHT, WIDTH, 4) float32, bottom row first, from the core's (slices, elevations,
    azimuths, 3) arrays."""
    shape = (SLICES, ELEVATIONS, AZIMUTHS, 3)
    if inscatter.shape != shape or optical_depth.shape != shape:
        raise ValueError(
            f"aerial table: arrays of shape {shape} expected, got {inscatter.shape} and {optical_depth.shape}"
        )
    atlas = np.ones((2, SLICES * ELEVATIONS, AZIMUTHS, 4), np.float32)
    atlas[0, ..., :3] = inscatter.reshape(SLICES * ELEVATIONS, AZIMUTHS, 3)
    atlas[1, ..., :3] = optical_depth.reshape(SLICES * ELEVATIONS, AZIMUTHS, 3)
    return atlas.reshape(HEIGHT, WIDTH, 4)


def coordinates(
    direction: np.ndarray,
    distance: np.ndarray,
    max_distance: float,
    linear_distance: float = LINEAR_DISTANCE_M,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v of the L texel of the nearer slice, w): the shader's arithmetic, per point.
    direction: (..., 3) unit vectors from the camera; distance: (...) in the same unit as
    max_distance and linear_distance. The other three texels are at v + ELEVATIONS / HEIGHT (the farther
    slice) and v + 1/2 (tau)."""
    x, y, z = direction[..., 0], direction[..., 1], direction[..., 2]
    u = np.arctan2(y, x) * (1.0 / (2.0 * math.pi)) + 0.5
    theta = np.arcsin(np.clip(z, -1.0, 1.0))
    e = np.sign(theta) * np.sqrt(np.abs(theta) * (2.0 / math.pi)) * 0.5 + 0.5
    row = e * (ELEVATIONS - 1) + 0.5
    c = math.log1p(max_distance / linear_distance) / (SLICES - 1)
    x = distance / linear_distance + 1.0
    s = np.minimum(np.log(x) / c, SLICES - 1)
    k0 = np.minimum(np.floor(s), SLICES - 2)
    w = np.clip((x * np.exp(-c * k0) - 1.0) / math.expm1(c), 0.0, 1.0)
    v = (k0 * ELEVATIONS + row) / HEIGHT
    return u, v, w


def _bilinear(atlas: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    fx, fy = u * WIDTH - 0.5, v * HEIGHT - 0.5
    x0, y0 = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
    ax, ay = (fx - x0)[..., None], (fy - y0)[..., None]
    x1, y1 = (x0 + 1) % WIDTH, np.minimum(y0 + 1, HEIGHT - 1)
    x0, y0 = x0 % WIDTH, np.maximum(y0, 0)
    rgb = atlas[..., :3]
    return (1 - ay) * ((1 - ax) * rgb[y0, x0] + ax * rgb[y0, x1]) + ay * (
        (1 - ax) * rgb[y1, x0] + ax * rgb[y1, x1]
    )


def lookup(
    atlas: np.ndarray,
    direction: np.ndarray,
    distance: np.ndarray,
    max_distance: float,
    linear_distance: float = LINEAR_DISTANCE_M,
) -> tuple[np.ndarray, np.ndarray]:
    """(L, T), (..., 3) each, as the material node group computes them."""
    u, v, w = coordinates(direction, distance, max_distance, linear_distance)
    w = w[..., None]
    far = ELEVATIONS / HEIGHT
    L = (1 - w) * _bilinear(atlas, u, v) + w * _bilinear(atlas, u, v + far)
    tau = (1 - w) * _bilinear(atlas, u, v + 0.5) + w * _bilinear(atlas, u, v + 0.5 + far)
    return L, np.exp(-tau)


# --- the screen table (Cycles) -------------------------------------------------------------
# welkin.aerial_screen_table() (aerial_table.hpp) gives, for the frame's camera, the table
# as three float RGBA textures on a lattice that repeats in every axis ("textures" and
# "lattice": AerialScreenTable::textures), so that the shader's arithmetic per sample is
# (screen_coordinates):
#     tau = log_B(d), B = ratio^slices     d: View Distance (View Z Depth: orthographic)
#     (u, v) = (x, y) * scale + snap(tau, (1, 1 / slices))   'Linear', 'Repeat'
#     L = mix(tex0, tex1, tau),  1 - T = mix(tex2, (tex0.a, tex1.a, tex2.a), tau)
# (mix(p, q, f) = (1 - f) p + f q, the Mix node's) with (x, y) the View Vector's
# (perspective) or the Window coordinate (0 .. 1 left to right, bottom to top): one
# logarithm, one snap, one multiply-add, three fetches, a combine and two mixes. The snap's x
# is floor(tau), an integer: it leaves a repeating texture's u as it is.
SCREEN_COLUMNS, SCREEN_ROWS = 32, 48
SCREEN_RATIO = 1.15
SCREEN_STEPS_PER_SLICE = 1
SCREEN_MARGIN_PX = 1.0  # beyond the pixel filter's half width


def screen_margins(width_px: int, height_px: int, filter_px: float) -> tuple[float, float]:
    """How far beyond the frame's edges samples fall (Window fractions): the pixel filter's
    half width and a pixel more."""
    reach = 0.5 * filter_px + SCREEN_MARGIN_PX
    return reach / width_px, reach / height_px


class ScreenLattice:
    """A baked screen table's lattice (welkin.aerial_screen_table()["lattice"]) and the
    constants of the shader's arithmetic."""

    def __init__(self, lattice: dict) -> None:
        self.coordinate = str(lattice["coordinate"])
        self.columns, self.rows = int(lattice["columns"]), int(lattice["rows"])
        self.slices = int(lattice["slices"])
        self.spacing_x, self.spacing_y = float(lattice["spacing_x"]), float(lattice["spacing_y"])
        self.ratio = float(lattice["ratio"])
        self.first_exponent = int(lattice["first_exponent"])

    @property
    def height(self) -> int:
        return self.rows * self.slices

    @property
    def log_base(self) -> float:
        return self.ratio**self.slices

    @property
    def snap(self) -> tuple[float, float, float]:
        return 1.0, 1.0 / self.slices, 1.0

    @property
    def scale(self) -> tuple[float, float, float]:
        return (1.0 / (self.columns * self.spacing_x), 1.0 / (self.slices * self.rows * self.spacing_y), 0.0)


def screen_coordinates(
    lattice: ScreenLattice, x: np.ndarray, y: np.ndarray, distance: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v, tau) as the material node group computes them (x, y: the lattice's
    coordinate; distance: scene units, > 0)."""
    tau = np.log(distance) / math.log(lattice.log_base)
    snap_x, snap_y, _ = lattice.snap
    scale_x, scale_y, _ = lattice.scale
    return (x * scale_x + np.floor(tau / snap_x) * snap_x, y * scale_y + np.floor(tau / snap_y) * snap_y, tau)


def _bilinear_repeat(image: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    H, W = image.shape[:2]
    fx, fy = u * W - 0.5, v * H - 0.5
    x0, y0 = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
    ax, ay = (fx - x0)[..., None], (fy - y0)[..., None]
    xa, xb, ya, yb = x0 % W, (x0 + 1) % W, y0 % H, (y0 + 1) % H
    rgba = image.astype(np.float64)
    return (1 - ay) * ((1 - ax) * rgba[ya, xa] + ax * rgba[ya, xb]) + ay * (
        (1 - ax) * rgba[yb, xa] + ax * rgba[yb, xb]
    )


def screen_lookup(
    lattice: ScreenLattice, textures: np.ndarray, x: np.ndarray, y: np.ndarray, distance: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(L, T), (..., 3) each, as the material node group computes them from the core's three
    textures ('Linear' fetches with 'Repeat', then the two mixes by tau)."""
    u, v, tau = screen_coordinates(lattice, x, y, distance)
    tau = tau[..., None]
    t0, t1, t2 = (_bilinear_repeat(t, u, v) for t in textures)
    L = (1.0 - tau) * t0[..., :3] + tau * t1[..., :3]
    far = np.stack([t0[..., 3], t1[..., 3], t2[..., 3]], axis=-1)
    opacity = (1.0 - tau) * t2[..., :3] + tau * far
    return L, 1.0 - opacity
