# SPDX-License-Identifier: Apache-2.0
"""welkin.sun()'s disc model (include/welkin/atmosphere/sun_disc.hpp), as a shader uses it:
the RGB limb-darkening polynomial integrated over the disc gives the direct irradiance
in RGB, and the spectral one gives direct_irradiance per wavelength."""

import numpy as np
import pytest

import welkin


def disc_integral(centre, coefficients, alpha, n=20000):
    """2 pi int_0^alpha sin(rho) L(rho) d rho, L = centre * sum_k a_k mu^k (midpoint rule)."""
    rho = (np.arange(n) + 0.5) * alpha / n
    s = np.sin(rho) / np.sin(alpha)
    mu = np.sqrt(np.clip(1.0 - s * s, 0.0, 1.0))
    poly = sum(coefficients[..., k, None] * mu**k for k in range(6))
    return 2 * np.pi * (np.sin(rho) * centre[..., None] * poly).sum(-1) * alpha / n


@pytest.mark.parametrize("preset", ["clear", "hazy"])
@pytest.mark.parametrize("elevation_deg", [45.0, 3.0])
def test_disc_energy_is_the_direct_irradiance(preset, elevation_deg):
    atm = welkin.Atmosphere.preset(preset)
    e = np.radians(elevation_deg)
    sun = welkin.sun(atm, 0.0, [np.cos(e), 0.0, np.sin(e)])
    alpha = sun.angular_radius_rad
    assert alpha == pytest.approx(atm.sun_angular_radius_rad)
    assert sun.solid_angle_sr == pytest.approx(2 * np.pi * (1 - np.cos(alpha)))
    np.testing.assert_allclose(sun.limb_coefficients.sum(1), 1.0, atol=2e-4)
    spectral = disc_integral(sun.centre_radiance, sun.limb_coefficients, alpha)
    np.testing.assert_allclose(spectral, sun.direct_irradiance, rtol=1e-3)
    rgb = disc_integral(sun.centre_radiance_rgb, sun.limb_coefficients_rgb, alpha)
    np.testing.assert_allclose(rgb, sun.direct_irradiance_rgb, rtol=1e-3)
    np.testing.assert_allclose(sun.mean_radiance * sun.solid_angle_sr, sun.direct_irradiance, rtol=1e-12)


def test_disc_below_the_horizon_is_dark():
    atm = welkin.Atmosphere.preset("clear")
    e = np.radians(-3.0)
    sun = welkin.sun(atm, 0.0, [np.cos(e), 0.0, np.sin(e)])
    assert sun.visible_fraction == 0.0
    assert np.all(sun.centre_radiance == 0.0)
    assert np.all(sun.centre_radiance_rgb == 0.0)
