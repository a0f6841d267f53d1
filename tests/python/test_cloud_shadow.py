# SPDX-License-Identifier: Apache-2.0
"""welkin.cloud_transmittance: the clouds' transmittance towards the sun from many points
(the add-on's Shade Sun Lamp and Ground Shadows). The march itself is checked against
Beer-Lambert in tests/cpp/test_cloud_shadow.cpp; here the binding: a layer shadows the
ground below it and not the air above it, the default direction is the scene's sun, a
clear scene gives ones, bad input names the parameter."""

import json

import numpy as np
import pytest

import welkin

LAYER = {
    "bottom_altitude_m": 1000.0,
    "top_altitude_m": 1800.0,
    "coverage": 1.0,
    "weather_variation": 0.0,
    "density_per_m": 0.002,
}


def scene(sun=(0.0, 0.5, 0.8660254037844386), layers=(LAYER,)):
    d = {"version": 1, "sun": {"direction": list(sun)}}
    if layers:
        d["clouds"] = {"layers": list(layers)}
    return json.dumps(d)


def test_layer_shadows_below_not_above():
    t = welkin.cloud_transmittance(scene(), [[0, 0, 0], [300, -20, 5], [0, 0, 2500]])
    assert t.shape == (3,) and t.dtype == np.float32
    assert 0.0 < t[0] < 0.9 and 0.0 < t[1] < 0.9
    assert t[2] == 1.0


def test_direction_default_is_the_scene_sun_and_lower_sun_is_darker():
    sun = np.array([0.0, 0.5, 0.8660254037844386])
    p = [[0.0, 0.0, 0.0]]
    assert welkin.cloud_transmittance(scene(), p)[0] == welkin.cloud_transmittance(scene(), p, sun)[0]
    low = welkin.cloud_transmittance(scene(), p, [0.0, 0.9, 0.2])[0]
    assert low < welkin.cloud_transmittance(scene(), p)[0]


def test_clear_scene_gives_ones():
    np.testing.assert_array_equal(welkin.cloud_transmittance(scene(layers=()), np.zeros((4, 3))), 1.0)


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="steps"):
        welkin.cloud_transmittance(scene(), [[0, 0, 0]], steps=0)
    with pytest.raises(ValueError, match="direction"):
        welkin.cloud_transmittance(scene(), [[0, 0, 0]], [0, 0, 0])
    with pytest.raises(ValueError, match="points"):
        welkin.cloud_transmittance(scene(), [[0, np.nan, 0]])
    with pytest.raises(ValueError, match="points"):
        welkin.cloud_transmittance(scene(), [[0, 0]])
    with pytest.raises(ValueError, match="max_distance_m"):
        welkin.cloud_transmittance(scene(), [[0, 0, 0]], max_distance_m=-1.0)
