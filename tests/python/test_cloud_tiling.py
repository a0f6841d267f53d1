# SPDX-License-Identifier: Apache-2.0
"""No tiling: a procedural layer seen over tens of its noise's periods does not repeat.

The layer reads periodic textures (clouds/noise.hpp): the weather map, one period every
weather_scale_m along the world's axes, and the base shape, one period every base_scale_m
along the streak direction (30 degrees off x, stretched by the type's `stretch`) and across
it. A texture read as it is repeats at those periods, and from above, over tens of periods,
the repetition reads as ribbing. The layers read them hex-tiled (noise.hpp, hex_taps).

The check: the map of the layer's vertical optical depth over a wide square (the view from
above) and its 2-D autocorrelation (Wiener-Khinchin, by FFT, zero-padded so that it is the
linear one, each lag normalised by its overlap). At every lattice vector of a tile (up to
twice each basis vector, either sign, no longer than half the map), the autocorrelation (the
largest of the 3 x 3 pixels about the lag, which falls between pixels) is compared with the
autocorrelation the same map has at lags of the same length (within 1.5 pixels) away from
the tile's lattice vectors (farther than a quarter period): it must stay within
Z_MAX = 4 of their standard deviations above their mean. A tile period is then no peak
above what the noise's own autocorrelation reaches at non-period lags. With the textures read
as they are (a plain wrapped lookup), the weather periods stand 5 to 38 standard deviations
out for every type, and the base periods of stratocumulus and altocumulus 5 to 7; hex-tiled,
the largest of the lags is 3.0 (docs/validation.md, "Tiling").
"""

import math

import numpy as np
import pytest

import welkin

# The type's streak stretch (clouds/procedural.cpp, shape_of) and the streak direction.
STRETCH = {"cumulus": 1.0, "stratocumulus": 1.6, "altocumulus": 1.0, "stratus": 1.5, "cirrus": 25.0}
STREAK = math.radians(30.0)
PIXELS = 384
R_PLANET = 6360e3
Z_MAX = 4.0


def depth_map(layer, pixel_m, steps=16):
    """The vertical optical depth of PIXELS x PIXELS columns `pixel_m` apart about the
    origin, each column along the local vertical of the curved shell (midpoint rule)."""
    xs = (np.arange(PIXELS) + 0.5 - PIXELS / 2) * pixel_m
    x, y = np.meshgrid(xs, xs, indexing="xy")
    up = np.stack([x, y, np.full_like(x, R_PLANET)], -1)
    up /= np.linalg.norm(up, axis=-1, keepdims=True)
    bottom, top = layer.bottom_altitude_m, layer.top_altitude_m
    dh = (top - bottom) / steps
    tau = np.zeros(x.shape)
    for k in range(steps):
        p = up * (R_PLANET + bottom + (k + 0.5) * dh)
        p[..., 2] -= R_PLANET
        tau += layer.sigma_t(p.reshape(-1, 3)).reshape(x.shape) * dh
    return tau


def autocorrelation(a):
    """The normalised linear autocorrelation of `a`, lag (0, 0) at the centre [n, n]."""
    a = a - a.mean()
    shape = (2 * a.shape[0], 2 * a.shape[1])
    f = np.fft.rfft2(a, s=shape)
    c = np.fft.irfft2(f * np.conj(f), s=shape)
    ones = np.fft.rfft2(np.ones_like(a), s=shape)
    overlap = np.fft.irfft2(ones * np.conj(ones), s=shape)
    c = np.fft.fftshift(c / np.maximum(np.round(overlap), 1.0))
    return c / c[a.shape[0], a.shape[1]]


def peaks_and_thresholds(c, pixel_m, basis):
    """For each lattice vector m a + k b (|m|, |k| <= 2, one of each +- pair) no longer than
    half the map: (its length, the autocorrelation there, the threshold: the mean plus Z_MAX
    standard deviations of the autocorrelation at non-period lags of that length)."""
    n = c.shape[0] // 2
    lag_y, lag_x = (np.mgrid[0 : 2 * n, 0 : 2 * n] - n) * pixel_m
    length = np.hypot(lag_x, lag_y)
    (ax, ay), (bx, by) = basis
    vectors = [
        (m * ax + k * bx, m * ay + k * by)
        for m in range(-2, 3)
        for k in range(-2, 3)
        if (m, k) > (0, 0) and math.hypot(m * ax + k * bx, m * ay + k * by) <= n * pixel_m / 2
    ]
    quarter = 0.25 * min(math.hypot(ax, ay), math.hypot(bx, by))
    near = np.zeros(c.shape, bool)
    for m in range(-5, 6):
        for k in range(-5, 6):
            near |= np.hypot(lag_x - (m * ax + k * bx), lag_y - (m * ay + k * by)) < quarter
    out = []
    for vx, vy in vectors:
        i, j = int(round(n + vy / pixel_m)), int(round(n + vx / pixel_m))
        at = c[i - 1 : i + 2, j - 1 : j + 2].max()
        r = math.hypot(vx, vy)
        ring = c[(np.abs(length - r) <= 1.5 * pixel_m) & ~near]
        assert ring.size >= 50, f"too few non-period lags of length {r:.0f} m"
        out.append((r, at, ring.mean() + Z_MAX * ring.std()))
    return out


@pytest.mark.parametrize("cloud_type", ["stratocumulus", "altocumulus", "cumulus", "stratus", "cirrus"])
def test_a_wide_view_from_above_has_no_peak_at_the_tile_periods(cloud_type):
    preset = welkin.cloud_type_preset(cloud_type)
    layer = welkin.CloudLayer(cloud_type=cloud_type, coverage=0.5)
    w = preset["weather_scale_m"]
    s = math.sqrt(STRETCH[cloud_type])
    b_along, b_across = preset["base_scale_m"] * s, preset["base_scale_m"] / s
    c, si = math.cos(STREAK), math.sin(STREAK)
    tiles = {
        # The weather map: 8 periods across the map.
        "weather": (w / 48.0, ((w, 0.0), (0.0, w))),
        # The base shape: 24 periods of its shorter side across the map.
        "base": (
            min(b_along, b_across) / 16.0,
            ((b_along * c, b_along * si), (-b_across * si, b_across * c)),
        ),
    }
    failures = []
    for tile, (pixel_m, basis) in tiles.items():
        c_map = autocorrelation(depth_map(layer, pixel_m))
        for r, at, threshold in peaks_and_thresholds(c_map, pixel_m, basis):
            if at > threshold:
                failures.append(f"{tile} lag {r:.0f} m: {at:.3f} > {threshold:.3f}")
    assert not failures, f"{cloud_type} repeats: " + "; ".join(failures)
