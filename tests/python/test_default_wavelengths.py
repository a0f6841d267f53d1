# SPDX-License-Identifier: Apache-2.0
"""The default wavelengths (620/560/480/440 nm) through the Python module: the preset's
channels, and sky_radiance(output="rgb") at the default against the 48-wavelength
spectral path in deep twilight (CIE xy within the tolerance of docs/validation.md)."""

import numpy as np

import welkin

RGB_TO_XYZ = np.array(
    [[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]]
)


def chromaticity(rgb):
    xyz = rgb @ RGB_TO_XYZ.T
    return xyz[:, :2] / xyz.sum(1)[:, None]


def test_default_preset_has_the_four_wavelengths():
    atm = welkin.Atmosphere.preset("clear")
    np.testing.assert_array_equal(atm.wavelengths_nm, [620.0, 560.0, 480.0, 440.0])
    assert atm.channels == 4


def test_twilight_rgb_matches_the_spectral_path():
    e = np.radians(-6.0)
    sun = [np.cos(e), 0.0, np.sin(e)]
    z = np.linspace(0.05, 1.0, 12)
    dirs = np.stack([np.sqrt(1 - z * z), np.zeros_like(z), z], 1)
    fast = welkin.sky_radiance(welkin.Atmosphere.preset("clear"), 0.0, sun, dirs, "lut", "rgb")
    spectral_atm = welkin.Atmosphere.preset("clear", welkin.spectral_wavelengths_nm())
    spectral = welkin.sky_radiance(spectral_atm, 0.0, sun, dirs, "lut", "rgb")
    err = np.linalg.norm(chromaticity(fast) - chromaticity(spectral), axis=1)
    assert np.median(err) <= 0.005 and err.max() <= 0.015
