# SPDX-License-Identifier: Apache-2.0
"""Never negative or non-finite light in RGB, for any preset, method, altitude or sun.

The spectral sweep (test_stability.py) checks the methods' radiance per wavelength; this one
checks what a renderer receives: the RGB of `sky_radiance`, of `sky_image` with the sun's
disc and the ground, and of `sun` (the lamp's colour and the disc's RGB limb polynomial).
The conversion to RGB is linear with negative matrix entries, so a positive spectrum can
give a negative channel; the gamut mapping (include/welkin/color/gamut.hpp) must bring every
one of them into Rec.709's gamut. Every method x preset x sun from -18 to 90 degrees x
observer from the ground to 100 km; the reference method runs with few paths (only finiteness
and sign matter here) on a thinner sweep.
"""

import math

import numpy as np
import pytest

import welkin

PRESETS = welkin.Atmosphere.preset_names()
SUNS_DEG = (-18.0, -12.0, -6.0, -2.0, 0.0, 1.0, 5.0, 20.0, 60.0, 90.0)
ALTITUDES_M = (0.0, 1000.0, 10e3, 100e3)
FAST_METHODS = ("analytic", "lut", "raymarch", "auto")


def sun_direction(elevation_deg, azimuth_deg=30.0):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


def directions(n=160):
    """A golden-angle spiral over the sphere, plus the horizon ring and the poles."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(1.0 - z * z)
    spiral = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    az = np.linspace(0.0, 2.0 * math.pi, 24, endpoint=False)
    ring = np.stack([np.cos(az), np.sin(az), np.zeros_like(az)], axis=1)
    poles = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    return np.ascontiguousarray(np.concatenate([spiral, ring, poles]))


DIRS = directions()


def assert_light(rgb, what):
    rgb = np.asarray(rgb)
    assert np.all(np.isfinite(rgb)), f"{what}: non-finite RGB"
    worst = float(rgb.min())
    assert worst >= 0.0, (
        f"{what}: negative RGB, down to {worst:.4g} at {np.argmin(rgb.min(-1) if rgb.ndim > 1 else rgb)}"
    )


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("method", FAST_METHODS)
def test_sky_radiance_rgb(preset, method):
    atm = welkin.Atmosphere.preset(preset)
    for altitude in ALTITUDES_M:
        for elevation in SUNS_DEG:
            rgb = welkin.sky_radiance(atm, altitude, sun_direction(elevation), DIRS, method, "rgb")
            assert_light(rgb, f"{preset} {method} {altitude} m sun {elevation} deg")


@pytest.mark.parametrize("preset", PRESETS)
def test_reference_rgb(preset):
    atm = welkin.Atmosphere.preset(preset)
    for altitude in (0.0, 100e3):
        for elevation in (-18.0, -4.0, 1.0, 30.0):
            rgb = welkin.sky_radiance(
                atm, altitude, sun_direction(elevation), DIRS[::8], "reference", "rgb", paths=4, seed=3
            )
            assert_light(rgb, f"{preset} reference {altitude} m sun {elevation} deg")


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("method", ("analytic", "lut", "raymarch"))
def test_sky_image_with_disc_and_ground(preset, method):
    atm = welkin.Atmosphere.preset(preset)
    for altitude in ALTITUDES_M:
        for elevation in SUNS_DEG:
            # 64 x 32: the disc (0.54 degrees) splats into its pixel at any width.
            img = welkin.sky_image(atm, altitude, sun_direction(elevation), 64, method, steps=16)
            assert_light(img.reshape(-1, 3), f"{preset} {method} {altitude} m sun {elevation} deg")


@pytest.mark.parametrize("preset", PRESETS)
def test_sun_lamp_and_disc(preset):
    atm = welkin.Atmosphere.preset(preset)
    for altitude in ALTITUDES_M:
        for elevation in np.concatenate([SUNS_DEG, np.linspace(-0.6, 8.0, 18)]):
            sun = welkin.sun(atm, altitude, sun_direction(float(elevation)))
            what = f"{preset} {altitude} m sun {elevation:.3f} deg"
            assert_light(sun.direct_irradiance_rgb, what + " lamp")
            assert_light(sun.centre_radiance_rgb, what + " disc centre")
            check_limb(sun.limb_coefficients_rgb, sun.limb_coefficients, what)


def check_limb(b, a, what):
    """The RGB limb polynomial is a physical profile: each channel's coefficients lie within
    the per-wavelength (Neckel & Labs) ones, sum to 1 (centre), and the profile is positive
    and darkens monotonically from the centre (mu = 1) to the limb (mu = 0)."""
    b, a = np.asarray(b), np.asarray(a)
    assert np.all(np.isfinite(b)), what
    np.testing.assert_allclose(b.sum(1), 1.0, atol=3e-4, err_msg=what)
    assert np.all(b >= a.min(0) - 1e-9) and np.all(b <= a.max(0) + 1e-9), f"{what}: {b}"
    mu = np.linspace(0.0, 1.0, 201)
    profile = sum(b[:, k, None] * mu**k for k in range(6))
    assert np.all(profile > 0.0), f"{what}: limb profile not positive"
    assert np.all(np.diff(profile, axis=1) > 0.0), f"{what}: limb profile not darkening to the limb"
