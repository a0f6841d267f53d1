# SPDX-License-Identifier: Apache-2.0
"""The night sky under clouds from the CLI and the module (night/moonlit_sky.hpp): `welkin
sky --scene S --time ...` is welkin.scene_sky_image of that scene with the moment's moon,
stars and night glow (the add-on's path), pixel for pixel; sky_image_at(clouds=...) shows
the stars through a gap of a layer and not through a thick overcast, and lights the clouds
with the moon; every value is finite and non-negative; bad night arguments are refused
naming the parameter.
"""

import json
import subprocess

import numpy as np
import pytest

import welkin

PARIS = (48.8566, 2.3522)
FULL_MOON_NIGHT = "2026-06-30T01:30:00+02:00"  # sun 17.8 degrees down, full moon 13 up (south)
MOONLESS = "2026-08-13T00:30:00+02:00"  # sun and moon 24 degrees down
LAYER = {
    "bottom_altitude_m": 1500.0,
    "top_altitude_m": 2500.0,
    "coverage": 0.5,
    "density_per_m": 0.05,
    "base_scale_m": 4000.0,
    "weather_scale_m": 12000.0,
    "seed": 5,
}


def _scene(tmp_path, layer=LAYER):
    scene = {
        "version": 1,
        "atmosphere": "bruneton2017",
        "method": "lut",
        "clouds": {"layers": [layer], "lighting": {"max_steps": 32, "light_steps": 4}},
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return path


def _read_rgb(path):
    pixels, names = welkin.read_exr(str(path))
    return pixels[..., [names.index(c) for c in "RGB"]].astype(np.float64)


def _cli(*args):
    from cli_testing import CLI

    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=300)


def _night_kwargs(time):
    """scene_sky_image's night arguments for Paris at `time` (+Y north, as the CLI's)."""
    pt = welkin.sun_and_moon(time, *PARIS)
    moon = pt["moon"]
    return pt, {
        "moon_direction": moon["direction"],
        "sun_from_moon": moon["sun_direction_from_moon"],
        "moon_angular_radius_rad": np.radians(moon["angular_radius_deg"]),
        "moon_irradiance_ratio": moon["irradiance_ratio"],
        "stars": welkin.stars_at(time, *PARIS),
        "night_glow": True,
        "time": time,
        "latitude_deg": PARIS[0],
        "longitude_deg": PARIS[1],
    }


def test_cli_scene_with_time_is_scene_sky_image_with_the_night(tmp_path):
    path = _scene(tmp_path)
    out = tmp_path / "night.exr"
    lat, lon = PARIS
    done = _cli(
        "sky",
        "--scene",
        path,
        "--time",
        FULL_MOON_NIGHT,
        "--latitude",
        lat,
        "--longitude",
        lon,
        "--width",
        "64",
        "-o",
        out,
    )
    assert done.returncode == 0, done.stderr
    cli = _read_rgb(out)
    pt, night = _night_kwargs(FULL_MOON_NIGHT)
    scene = json.loads(path.read_text())
    scene["sun"] = {"direction": pt["sun"]["direction"]}
    text = json.dumps(scene)
    module = welkin.scene_sky_image(text, 64, **night).astype(np.float64)
    assert np.isfinite(cli).all() and (cli >= 0.0).all()
    assert np.abs(cli - module).max() <= 1e-5 * module.max()
    # The night is there: without it (the sun's sky of 17.8 degrees down alone) the image
    # is darker, most of all where the moon lights the clouds.
    dark, t = welkin.scene_sky_image(text, 64, return_transmittance=True)
    assert (module >= dark - 1e-6 * module.max()).all()
    cloudy = t < 0.1
    assert cloudy.sum() > 20 and (t > 0.99).sum() > 20
    assert module[cloudy].sum() > 100.0 * dark[cloudy].sum()


def test_sky_image_at_shows_stars_through_gaps_only():
    atm = welkin.Atmosphere.preset("bruneton2017")
    layer = welkin.CloudLayer(**LAYER)
    args = (atm, MOONLESS, *PARIS, 256)
    with_stars = welkin.sky_image_at(*args, clouds=layer).astype(np.float64)
    without = welkin.sky_image_at(*args, clouds=layer, stars=False).astype(np.float64)
    assert np.isfinite(with_stars).all() and (with_stars >= 0.0).all()
    starlight = (with_stars - without).sum(axis=2)
    clear = welkin.star_image(atm, welkin.stars_at(MOONLESS, *PARIS), 256).astype(np.float64).sum(axis=2)
    scene = {"version": 1, "atmosphere": "bruneton2017", "method": "lut", "clouds": {"layers": [LAYER]}}
    scene["sun"] = {"direction": welkin.sun_and_moon(MOONLESS, *PARIS)["sun"]["direction"]}
    _img, t = welkin.scene_sky_image(json.dumps(scene), 256, return_transmittance=True)
    gaps, overcast = (t > 0.99) & (clear > 0.0), (t < 0.01) & (clear > 0.0)
    assert gaps.sum() > 50 and overcast.sum() > 50, (gaps.sum(), overcast.sum())
    # In the gaps every star is as bright as in a clear sky; behind thick cloud each is
    # dimmed by the cloud's transmittance there (under 1 %).
    np.testing.assert_allclose(starlight[gaps], clear[gaps] * t[gaps], rtol=1e-3, atol=1e-6 * clear.max())
    assert (starlight[overcast] <= 0.01 * clear[overcast] + 1e-6 * clear.max()).all()
    assert starlight[gaps].sum() > 0.9 * clear[gaps].sum()


def test_sky_image_at_lights_the_clouds_with_the_moon():
    # Full moon 13 degrees up, sun 17.8 down: the clouds are lit by both; the moon's part
    # is the clouds a sun in the moon's direction lights, times the moon's ratio.
    atm = welkin.Atmosphere.preset("bruneton2017")
    layer = welkin.CloudLayer(**LAYER)
    pt = welkin.sun_and_moon(FULL_MOON_NIGHT, *PARIS)
    img = welkin.sky_image_at(
        atm, FULL_MOON_NIGHT, *PARIS, 64, clouds=layer, discs=False, stars=False, night_glow=False
    ).astype(np.float64)
    sun = welkin.sky_image(atm, 0.0, pt["sun"]["direction"], 64, clouds=layer, sun_disc=False)
    moon = welkin.sky_image(atm, 0.0, pt["moon"]["direction"], 64, clouds=layer, sun_disc=False)
    expected = sun.astype(np.float64) + pt["moon"]["irradiance_ratio"] * moon.astype(np.float64)
    assert np.abs(img - expected).max() <= 1e-5 * expected.max()
    assert (img - sun).sum() > 0.5 * (img.sum())  # the moon outshines the sun's twilight here


def test_scene_sky_image_night_bad_input_names_the_parameter():
    scene = json.dumps({"version": 1, "method": "lut"})
    stars = np.array([[0.0, 0.0, 1.0, 2.0, 0.5]])
    for kwargs, name in [
        (
            {"moon_direction": (0.0, 0.0, 0.0), "sun_from_moon": (0, 0, 1), "moon_irradiance_ratio": 1e-6},
            "moon_direction",
        ),
        ({"moon_direction": (0.0, 0.0, 1.0), "moon_irradiance_ratio": 1e-6}, "sun_from_moon"),
        (
            {"moon_direction": (0, 0, 1), "sun_from_moon": (0, 0, -1), "moon_irradiance_ratio": 1.0},
            "moon.irradiance_ratio",
        ),
        (
            {"moon_direction": (0, 0, 1), "sun_from_moon": (0, 0, -1), "moon_angular_radius_rad": 1.0},
            "moon.angular_radius_rad",
        ),
        ({"stars": np.zeros((3, 4))}, "stars"),
    ]:
        with pytest.raises(ValueError, match=name.replace(".", r"\.")):
            welkin.scene_sky_image(scene, 16, **kwargs)
    assert welkin.scene_sky_image(scene, 16, stars=stars, night_glow=True).shape == (8, 16, 3)
