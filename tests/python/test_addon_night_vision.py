# SPDX-License-Identifier: Apache-2.0
"""The numbers of the add-on's Night Vision group (addon/welkin/night_vision.py) against
published values: the RGB -> XYZ matrices against IEC 61966-2-1's sRGB matrix (four
decimals) and each space's white against D65, the acuity fit at its quoted points, the
blur's radius, and bad input refused with the parameter's name."""

import math

import numpy as np
import pytest
from welkin_addon import night_vision as nv  # noqa: E402 (conftest loads it)

D65 = np.array([0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290])


def test_rec709_matrix_is_srgb():
    srgb = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    assert np.abs(np.array(nv.rgb_to_xyz("rec709")) - srgb).max() < 6e-5


@pytest.mark.parametrize("space", ["rec709", "rec2020", "acescg"])
def test_white_is_d65_with_unit_luminance(space):
    m = np.array(nv.rgb_to_xyz(space))
    assert np.abs(m @ np.ones(3) - D65).max() < 1e-6
    assert np.abs(np.array(nv.inverse(nv.rgb_to_xyz(space))) @ m - np.eye(3)).max() < 1e-12


def test_acuity():
    # Ward Larson et al. 1997's fit: 17.25 atan(1.4 log10 L + 0.35) + 25.72.
    assert nv.acuity_cycles_per_degree(1e-2) == pytest.approx(17.25 * math.atan(-2.45) + 25.72)
    assert 5.2 < nv.acuity_cycles_per_degree(1e-2) < 5.4
    assert 47.0 < nv.acuity_cycles_per_degree(100.0) < 48.0
    # A 39.6 degree lens at 1920 px: 48.5 px per degree, one period at 5.31 c/deg.
    ppd = nv.pixels_per_degree("PERSP", math.radians(39.6), 1920)
    assert nv.acuity_blur_px(ppd) == pytest.approx(1920 / 39.6 / nv.acuity_cycles_per_degree(1e-2))
    assert nv.pixels_per_degree("ORTHO", 0.5, 1920) == 0.0
    assert nv.pixels_per_degree("PANO", 0.0, 3600, math.radians(360.0)) == pytest.approx(10.0)


def test_luminance_scale():
    assert nv.luminance_scale(1.0) == 683.0
    assert nv.luminance_scale(100.0) == pytest.approx(6.83)


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: nv.luminance_scale(0.0), "exposure"),
        (lambda: nv.luminance_scale(float("nan")), "exposure"),
        (lambda: nv.acuity_blur_px(-1.0), "pixels_per_degree"),
        (lambda: nv.rgb_to_xyz("srgb"), "color_space"),
    ],
)
def test_bad_input_names_the_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()
