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


# --- the screen table (Cycles) -------------------------------------------------------------
# welkin.aerial_screen_table() (aerial_table.hpp) gives, for the frame's camera, the table
# as four float RGBA textures ("textures": AerialScreenTable::step_textures), each
# `columns` wide and rows x slices tall, rows counted from the bottom (Blender's order),
# tile k = rows [k rows, (k + 1) rows) holding slice k: L and the opacity 1 - T, each
# extrapolated to t = 0 along its step to the next slice, and the two steps, so that one
# texture coordinate reads a slice and the passes are value + t step: one vector
# multiply-add each. The shader's arithmetic, per sample (screen_coordinates):
#     t = log_ratio(d)                    d: View Distance, scene units
#     k = floor(t)                        the slice below d is k - first_exponent
#     (x, y) = (ax u + bx, ay v + by + (k - first_exponent) / slices)
# with (u, v) the Window coordinate (0 .. 1 left to right, bottom to top); the first slice
# lies at ratio^first_exponent scene units, so that the integer part of t is the slice.
SCREEN_COLUMNS, SCREEN_ROWS = 32, 48
SCREEN_RATIO = 1.15
SCREEN_STEPS_PER_SLICE = 1
SCREEN_RANGE = 1e5  # the first slice lies no nearer than clip end / SCREEN_RANGE
SCREEN_MARGIN_PX = 1.0  # beyond the pixel filter's half width


class ScreenLayout:
    """The screen table's layout for one camera and render (plain numbers)."""

    def __init__(self, width_px: int, height_px: int, filter_px: float, clip_start: float,
                 clip_end: float, columns: int = SCREEN_COLUMNS, rows: int = SCREEN_ROWS,
                 ratio: float = SCREEN_RATIO) -> None:
        if not (clip_end > clip_start > 0.0):
            raise ValueError(f"aerial screen table: the clip range {clip_start} .. {clip_end} "
                             "must be positive and increasing")
        self.columns, self.rows, self.ratio = columns, rows, ratio
        reach = 0.5 * filter_px + SCREEN_MARGIN_PX  # how far outside the frame samples fall, px
        self.margin_x, self.margin_y = reach / width_px, reach / height_px
        log_r = math.log(ratio)
        first = max(clip_start, clip_end / SCREEN_RANGE)
        self.first_exponent = math.floor(math.log(first) / log_r)
        self.slices = math.ceil(math.log(clip_end) / log_r - self.first_exponent) + 2
        self.first_distance = ratio ** self.first_exponent  # scene units

    @property
    def height(self) -> int:
        return self.rows * self.slices

    def affine(self) -> tuple[float, float, float, float]:
        """(ax, bx, ay, by) of the texture coordinate in the Window coordinate (slice 0)."""
        C, R, S = self.columns, self.rows, self.slices
        ax = (C - 1) / (C * (1.0 + 2.0 * self.margin_x))
        bx = (0.5 + self.margin_x * (C - 1) / (1.0 + 2.0 * self.margin_x)) / C
        ay = (R - 1) / (S * R * (1.0 + 2.0 * self.margin_y))
        by = (0.5 + self.margin_y * (R - 1) / (1.0 + 2.0 * self.margin_y)) / (S * R)
        return ax, bx, ay, by

    def key(self) -> str:
        return (f"{self.columns}x{self.rows}x{self.slices}/{self.margin_x!r}/{self.margin_y!r}/"
                f"{self.first_exponent}/{self.ratio!r}")


def screen_coordinates(layout: ScreenLayout, u: np.ndarray, v: np.ndarray, distance: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, t): the texture coordinate of the slice below the distance and the slice
    coordinate, as the material node group computes them (u, v: Window; distance: scene
    units, > 0)."""
    ax, bx, ay, by = layout.affine()
    t = np.log(distance) / math.log(layout.ratio)
    y = ay * v + by + (np.floor(t) - layout.first_exponent) / layout.slices
    return ax * u + bx, y, t


def _bilinear_extend(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    H, W = image.shape[:2]
    fx, fy = x * W - 0.5, y * H - 0.5
    x0, y0 = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
    ax, ay = (fx - x0)[..., None], (fy - y0)[..., None]
    xa, xb = np.clip(x0, 0, W - 1), np.clip(x0 + 1, 0, W - 1)
    ya, yb = np.clip(y0, 0, H - 1), np.clip(y0 + 1, 0, H - 1)
    rgb = image[..., :3].astype(np.float64)
    return ((1 - ay) * ((1 - ax) * rgb[ya, xa] + ax * rgb[ya, xb])
            + ay * ((1 - ax) * rgb[yb, xa] + ax * rgb[yb, xb]))


def screen_lookup(layout: ScreenLayout, textures: np.ndarray, u: np.ndarray, v: np.ndarray,
                  distance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(L, T), (..., 3) each, as the material node group computes them from the core's four
    textures ('Linear' fetches with 'Extend', then value + t step)."""
    x, y, t = screen_coordinates(layout, u, v, distance)
    t = t[..., None]
    L = _bilinear_extend(textures[0], x, y) + t * _bilinear_extend(textures[1], x, y)
    opacity = _bilinear_extend(textures[2], x, y) + t * _bilinear_extend(textures[3], x, y)
    return L, 1.0 - opacity
