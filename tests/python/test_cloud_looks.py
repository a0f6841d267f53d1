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
  above falls to a quarter at a lag along its longest direction (the fibres', which curve
  with the hooks: searched every 10 degrees) at least three times the lag across it; the
  cells of cumulus are round (the same ratio under 1.6).
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


def dense_extent(sigma, density_per_m):
    """Where the density reaches half the layer's largest (sigma_t >= density_per_m / 2): the
    dense map, and per column the indices of its first and last dense height (0 and the last
    height where a column has none)."""
    dense = sigma >= 0.5 * density_per_m
    first = np.argmax(dense, axis=-1)
    last = dense.shape[-1] - 1 - np.argmax(dense[..., ::-1], axis=-1)
    return dense, first, last


@pytest.mark.parametrize("cloud_type", ["cumulus", "stratocumulus", "altocumulus"])
def test_cells_have_flat_bases_under_tops_of_many_heights(cloud_type):
    preset = welkin.cloud_type_preset(cloud_type)
    layer = welkin.CloudLayer(cloud_type=cloud_type)
    thickness = preset["top_altitude_m"] - preset["bottom_altitude_m"]
    sigma, heights, dh = density_columns(layer, 12.0 * preset["base_scale_m"], 96, 160)
    tau = sigma.sum(axis=-1) * dh
    body = tau >= 2.0
    assert body.sum() >= 100, f"only {body.sum()} cloud columns"
    _, first, last = dense_extent(sigma, preset["density_per_m"])
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
    lags = {a: quarter_lag(c, span / n, math.radians(a)) for a in range(0, 180, 10)}
    longest = max(lags, key=lags.get)
    along = lags[longest]
    across = quarter_lag(c, span / n, math.radians(longest + 90))
    ratio = along / across
    print(
        f"{cloud_type}: quarter-correlation lag {along:.0f} m along its longest direction ({longest} degrees),"
        f" {across:.0f} m across: {ratio:.2f}"
    )
    assert lo <= ratio <= hi


def box_blur(image, k):
    """The k x k box mean (k odd) of a 2-D array, edges clamped."""
    r = k // 2
    padded = np.pad(image, r, mode="edge")
    c = np.cumsum(np.cumsum(np.pad(padded, ((1, 0), (1, 0))), 0), 1)
    h, w = image.shape
    return (c[k : k + h, k : k + w] - c[:h, k : k + w] - c[k : k + h, :w] + c[:h, :w]) / (k * k)


def overcast_fine_structure(elevation_deg, azimuth_deg, width, height, sky_rows):
    """An overcast stratus seen from the ground, camera 20 m up looking 15 degrees up, the sun
    at (elevation, azimuth right of the view): the fine structure of the luminance, the
    standard deviation of the top sky_rows less their 9-pixel box mean, over their mean."""
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    turn = math.radians(90.0 + 15.0)
    scene = {
        "version": 1,
        "atmosphere": "bruneton2017",
        "sun": {"direction": [math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)]},
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
        "resolution": {"x": width, "y": height, "percentage": 100},
        "clouds": {"layers": [{"cloud_type": "stratus", "coverage": 1.0}], "lighting": {"max_steps": 96}},
    }
    rgb = np.asarray(welkin.camera_plate(json.dumps(scene))["combined"], np.float64)[..., :3]
    sky = (rgb @ np.array([0.2126, 0.7152, 0.0722]))[:sky_rows]
    assert np.isfinite(sky).all() and sky.min() > 0.0
    return float(np.std(sky - box_blur(sky, 9)) / sky.mean())


def test_an_overcast_deck_from_below_has_no_streaks():
    """An overcast stratus seen from the ground (the contact sheet's noon view: sun 60 degrees
    up, 60 degrees right of the view, camera 15 degrees up), 480 x 270, is an even grey: its
    fine structure stays under 0.004. Shadow grids turned to the sun whose lines cut the
    deck's flat base at a slant drew streaks along the sun's azimuth there (0.0070 on the
    earlier shapes; 0.0032 for an anti-sun grid turned to -s without its near field); a grid
    of world axes read 0.0024, the turned grid with its near field 0.0025."""
    fine = overcast_fine_structure(60.0, 60.0, 480, 270, 200)
    print(f"overcast stratus from below: fine structure {fine:.4f} of the mean")
    assert fine < 0.004


@pytest.mark.parametrize("elevation_deg", [3.0, 8.0])
def test_an_overcast_deck_under_a_low_sun_has_no_wedges(elevation_deg):
    """The same deck at sunset (the contact sheet's view: sun 3 degrees up, 45 degrees right of
    the view; and 8 degrees up), 400 x 225: the fine structure stays under 0.0065. An anti-sun
    grid turned to a low sun runs nearly along the deck's base, and its lines drew dark
    wedges fanning from the sun's azimuth (0.0155 at 3 degrees, 0.0082 at 8); the grid of
    world axes it falls back to there reads 0.0061 and 0.0057. Of that, the deck's own
    texture near the horizon, where the view steps through it are longest: lit at the
    surface cut's pieces (lighting.hpp, "The surface"), not one long step inside, it reads
    0.0061 where the base step alone read 0.0060 (seeds 1-4 within 0.00004)."""
    fine = overcast_fine_structure(elevation_deg, 45.0, 400, 225, 170)
    print(f"overcast stratus, sun {elevation_deg:g} deg up: fine structure {fine:.4f} of the mean")
    assert fine < 0.0065


def test_cumulus_heaps_narrow_upwards():
    """The atlas's cumulus are heaps: mounds and domes over a flat base, narrower at the top
    than at the base (a paraboloid heap's width at height z shrinks as 1 - sqrt(1 - z / H)).
    The area of the horizontal cross-section of the dense cloud (sigma_t at least half the
    densest) over a square of columns, at a quarter and at half of H (the 90th percentile of
    the columns' tops) over its area at a tenth of H, stays under 0.87 and 0.6. Heaps with
    near-vertical sides under flattened or overhanging tops (boxes and mushrooms) keep most
    of their base's area up to half their height (0.93 and 0.70)."""
    preset = welkin.cloud_type_preset("cumulus")
    layer = welkin.CloudLayer(cloud_type="cumulus")
    sigma, heights, _ = density_columns(layer, 3.0 * preset["base_scale_m"], 200, 100)
    dense, _, last = dense_extent(sigma, preset["density_per_m"])
    body = dense.any(axis=-1)
    top = np.percentile(heights[last[body]], 90)
    area = dense.mean(axis=(0, 1))

    def at(z):
        return float(np.interp(z, heights, area))

    quarter, half = at(0.25 * top) / at(0.1 * top), at(0.5 * top) / at(0.1 * top)
    print(f"cumulus: tops to {top:.0f} m; area at 1/4 and 1/2 of it over at 1/10: {quarter:.2f}, {half:.2f}")
    assert quarter < 0.87
    assert half < 0.6


def connected_cells(mask):
    """Labels of the 4-connected regions of a 2D boolean map (0 outside), and their count."""
    labels = np.zeros(mask.shape, dtype=int)
    count = 0
    for start in zip(*np.nonzero(mask)):
        if labels[start]:
            continue
        count += 1
        labels[start] = count
        stack = [start]
        while stack:
            i, j = stack.pop()
            for a, b in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)):
                if 0 <= a < mask.shape[0] and 0 <= b < mask.shape[1] and mask[a, b] and not labels[a, b]:
                    labels[a, b] = count
                    stack.append((a, b))
    return labels, count


@pytest.mark.parametrize("cloud_type", ["cumulus", "stratocumulus", "altocumulus"])
def test_cells_are_domes_not_tents(cloud_type):
    """The atlas's heaps are mounds and domes. A heap whose top is read from its footprint's
    strength alone is a paraboloid under each cell's peak, tall for the small cells, and
    reads as a tent; a dome is fuller. Over a square of columns of the heaps without their
    lobes (detail_strength 0), each cell (a 4-connected region of columns with dense cloud,
    sigma_t at least half the densest) of height H (its highest column's top) keeps a share
    of its footprint above H / 2: 0.25 for a cone, 0.5 for a paraboloid of revolution, 0.685
    for the heap's profile u^0.6 and 0.75 for the cap of an ellipsoid, 1 for a box. Cells
    that touch count as one, under the higher one's H, and the widest cells flatten at the
    local top, so a sky's shares read between the closed forms: the paraboloid heaps read
    0.52-0.57 (cumulus, stratocumulus, altocumulus), the domes 0.60-0.69. The median cell's
    share stays above 0.58, and under 0.9: narrower upwards than a box."""
    preset = welkin.cloud_type_preset(cloud_type)
    layer = welkin.CloudLayer(cloud_type=cloud_type, detail_strength=0.0)
    sigma, heights, dh = density_columns(layer, 3.0 * preset["base_scale_m"], 240, 100)
    dense, _, last = dense_extent(sigma, preset["density_per_m"])
    body = dense.any(axis=-1)
    top = np.where(body, heights[last] + 0.5 * dh, 0.0)
    labels, count = connected_cells(body)
    shares = []
    for c in range(1, count + 1):
        tops = top[labels == c]
        if tops.size >= 30:  # a cell over a few columns has no profile to speak of
            shares.append(np.mean(tops >= 0.5 * tops.max()))
    share = float(np.median(shares))
    print(
        f"{cloud_type}: {len(shares)} cells; median share of the footprint above half the height {share:.3f}"
    )
    assert len(shares) >= 20
    assert 0.58 < share < 0.9


def shift_of_best_match(a, b, pixel_m):
    """The plane shift (m, x and y) that moves map a onto map b best: the peak of their
    circular cross-correlation (FFT), refined by a parabola through the peak's neighbours."""
    fa, fb = np.fft.fft2(a - a.mean()), np.fft.fft2(b - b.mean())
    c = np.real(np.fft.ifft2(np.conj(fa) * fb))
    n = c.shape[0]
    i, j = np.unravel_index(np.argmax(c), c.shape)

    def refine(m, z, p):
        return (m - p) / (2.0 * (m - 2.0 * z + p)) if (m - 2.0 * z + p) < 0 else 0.0

    di = refine(c[(i - 1) % n, j], c[i, j], c[(i + 1) % n, j])
    dj = refine(c[i, (j - 1) % n], c[i, j], c[i, (j + 1) % n])
    sy, sx = (i + di + n / 2) % n - n / 2, (j + dj + n / 2) % n - n / 2
    return np.array([sx, sy]) * pixel_m


def test_cirrus_fallstreaks_hook_and_strands_show_from_above():
    """Cirrus uncinus (the atlas): fibres ending in a hook or tuft at the top, their trails
    fallstreaks of ice drifting in a wind whose shear turns with height. Two properties of
    the density:
    * the trails drift and curve: the plane shift that best matches the heads' level (the
      density map at 0.88 of the layer) to the levels 0.15, 0.3 and 0.5 of the way down is
      the trails' drift at that depth; it grows with the depth (from at least 100 m), and its
      direction turns by more than 15 degrees between the trail's start (the head to 0.15)
      and its lower part (0.3 to 0.5): a hook (a drift in line with the streaks, or none,
      fails);
    * the strands are optically thick enough to be seen against the ground from above: the
      densest tenth of the cirrus columns (vertical optical depth above 0.01) reaches 1.3
      (73 % of the light stopped), where uniformly thin streaks stay under 1 (0.94)."""
    preset = welkin.cloud_type_preset("cirrus")
    layer = welkin.CloudLayer(cloud_type="cirrus")
    bottom, top = preset["bottom_altitude_m"], preset["top_altitude_m"]
    span, n = 16000.0, 256
    xs = (np.arange(n) + 0.5 - n / 2) * span / n
    x, y = np.meshgrid(xs, xs, indexing="xy")

    def level(f):
        p = np.stack([x, y, np.full_like(x, bottom + f * (top - bottom))], -1).reshape(-1, 3)
        return np.asarray(layer.sigma_t(p)).reshape(x.shape)

    head = level(0.88)
    drift = [shift_of_best_match(head, level(0.85 * (1.0 - s)), span / n) for s in (0.15, 0.3, 0.5)]
    reach = [float(np.linalg.norm(d)) for d in drift]
    assert 100.0 < reach[0] < reach[1] < reach[2], reach
    upper, lower = drift[0], drift[2] - drift[1]
    turn = math.degrees(math.acos(np.dot(upper, lower) / (np.linalg.norm(upper) * np.linalg.norm(lower))))
    print(
        f"cirrus: drift {[f'({d[0]:.0f}, {d[1]:.0f})' for d in drift]} m; the trail turns {turn:.0f} degrees"
    )
    assert turn > 15.0

    sigma, _, dh = density_columns(layer, 20000.0, 200, 30)
    tau = sigma.sum(axis=-1) * dh
    p90 = float(np.percentile(tau[tau > 0.01], 90))
    print(f"cirrus: 90th percentile of the columns' optical depth {p90:.2f}")
    assert p90 > 1.3
