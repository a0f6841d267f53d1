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
the shader's nodes are built from the same formulas (blender/aerial_frame.py).
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
    air = 2.0 * math.sqrt(max(top_radius_m ** 2 - bottom_radius_m ** 2, 1.0))
    return float(max(min(clip_end_m, air), 1.0))


def atlas_pixels(inscatter: np.ndarray, optical_depth: np.ndarray) -> np.ndarray:
    """(HEIGHT, WIDTH, 4) float32, bottom row first, from the core's (slices, elevations,
    azimuths, 3) arrays."""
    shape = (SLICES, ELEVATIONS, AZIMUTHS, 3)
    if inscatter.shape != shape or optical_depth.shape != shape:
        raise ValueError(f"aerial table: arrays of shape {shape} expected, got "
                         f"{inscatter.shape} and {optical_depth.shape}")
    atlas = np.ones((2, SLICES * ELEVATIONS, AZIMUTHS, 4), np.float32)
    atlas[0, ..., :3] = inscatter.reshape(SLICES * ELEVATIONS, AZIMUTHS, 3)
    atlas[1, ..., :3] = optical_depth.reshape(SLICES * ELEVATIONS, AZIMUTHS, 3)
    return atlas.reshape(HEIGHT, WIDTH, 4)


def coordinates(direction: np.ndarray, distance: np.ndarray, max_distance: float,
                linear_distance: float = LINEAR_DISTANCE_M
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
    return ((1 - ay) * ((1 - ax) * rgb[y0, x0] + ax * rgb[y0, x1])
            + ay * ((1 - ax) * rgb[y1, x0] + ax * rgb[y1, x1]))


def lookup(atlas: np.ndarray, direction: np.ndarray, distance: np.ndarray, max_distance: float,
           linear_distance: float = LINEAR_DISTANCE_M) -> tuple[np.ndarray, np.ndarray]:
    """(L, T), (..., 3) each, as the material node group computes them."""
    u, v, w = coordinates(direction, distance, max_distance, linear_distance)
    w = w[..., None]
    far = ELEVATIONS / HEIGHT
    L = (1 - w) * _bilinear(atlas, u, v) + w * _bilinear(atlas, u, v + far)
    tau = (1 - w) * _bilinear(atlas, u, v + 0.5) + w * _bilinear(atlas, u, v + 0.5 + far)
    return L, np.exp(-tau)
