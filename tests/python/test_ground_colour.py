# SPDX-License-Identifier: Apache-2.0
"""The ground below the horizon takes the preset's or the user's albedo colour.

The lit ground (include/welkin/atmosphere/ground.hpp) is L = L_path + T albedo / pi
(E_sun + E_sky). Seen from the ground itself (observer at 0 m, looking down: no air in
between, T = 1, L_path = 0), the radiance of a ground of albedo R over that of a grey ground
of the same mean albedo under the same sky is R weighted by the light, so the ratio's
chromaticity (r / (r + g + b)) is the chosen colour's. The grey has the colour's mean so
that the light the ground sends up and the sky sends back (E_sky grows with the ground's
albedo, channel by channel) is nearly the same in both: against a white ground it is not,
and the ratio comes out 2-4 % more saturated in chromaticity. What is left, measured 0.013
at most at both four and 48 wavelengths, is daylight's own colour across each channel's
band (the colour is defined under a flat spectrum, include/welkin/color/reflectance.hpp);
the tolerance is 0.02.

Also: the presets' own spectral albedos show through (clear_day's vegetation is green, the
desert's sand warm), and a grey keeps equal channels.
"""

import math

import numpy as np
import pytest

import welkin

SUN = (math.cos(math.radians(40.0)), 0.0, math.sin(math.radians(40.0)))
WIDTH = 64


def ground_rgb(atm):
    """Mean RGB of the rows looking 60-90 degrees down, from the ground (no disc)."""
    img = welkin.sky_image(atm, 0.0, SUN, WIDTH, method="lut", sun_disc=False)
    h = img.shape[0]
    assert np.all(np.isfinite(img)) and np.all(img >= 0.0)
    return img[h - h // 6 :].reshape(-1, 3).astype(np.float64).mean(axis=0)


def with_albedo(preset, spectral, albedo):
    atm = (
        welkin.Atmosphere.preset(preset, welkin.spectral_wavelengths_nm())
        if spectral
        else welkin.Atmosphere.preset(preset)
    )
    atm.ground_albedo = albedo(atm.wavelengths_nm) if callable(albedo) else [albedo] * atm.channels
    atm.validate()
    return atm


def chroma(rgb):
    rgb = np.asarray(rgb, dtype=np.float64)
    return rgb / rgb.sum()


@pytest.mark.parametrize("spectral", [False, True])
@pytest.mark.parametrize(
    "colour", [(0.40, 0.25, 0.10), (0.10, 0.30, 0.12), (0.15, 0.20, 0.45), (0.60, 0.55, 0.50)]
)
def test_ground_follows_the_chosen_colour(colour, spectral):
    mean = sum(colour) / 3.0
    grey = ground_rgb(with_albedo("clear_day", spectral, mean)) / mean
    atm = with_albedo("clear_day", spectral, lambda w: welkin.rgb_to_reflectance(colour, w))
    got = chroma(ground_rgb(atm) / grey)
    assert np.max(np.abs(got - chroma(colour))) < 0.02, (got, chroma(colour))


def test_a_grey_ground_is_the_flat_albedo():
    flat = ground_rgb(with_albedo("clear_day", False, 0.3))
    grey = ground_rgb(
        with_albedo("clear_day", False, lambda w: welkin.rgb_to_reflectance((0.3, 0.3, 0.3), w))
    )
    np.testing.assert_array_equal(grey, flat)
    # Against a white ground: 0.3 of it, less the light a darker ground no longer sends up
    # and the sky sends back, which is more in the blue, where the air scatters more.
    ratio = grey / ground_rgb(with_albedo("clear_day", False, 1.0))
    assert np.all(ratio <= 0.3 + 1e-6) and np.all(ratio > 0.2), ratio
    assert ratio[0] > ratio[1] > ratio[2], ratio


@pytest.mark.parametrize(
    "preset, check",
    [
        ("clear_day", lambda r: r[1] > r[0] and r[1] > r[2]),  # vegetation: green
        ("desert_dust", lambda r: r[0] > r[1] > r[2]),  # sand: warm
    ],
)
def test_the_presets_ground_shows_its_colour(preset, check):
    white = ground_rgb(with_albedo(preset, False, 1.0))
    own = ground_rgb(welkin.Atmosphere.preset(preset))
    ratio = own / white
    assert check(ratio), ratio


def test_bad_colour_names_the_parameter():
    for bad in ((1.2, 0.1, 0.1), (-0.1, 0.1, 0.1), (0.1, math.nan, 0.1), (0.1, 0.2)):
        with pytest.raises(ValueError, match="ground_color"):
            welkin.rgb_to_reflectance(bad, [550.0])


def test_the_command_line_ground_colour_is_the_modules(tmp_path):
    """`welkin sky --ground-color R,G,B` renders what the module renders with that colour's
    reflectance as the atmosphere's ground albedo (the ground and the sky it lights), in the
    output's colour space; a bad colour is refused, naming the option and its range."""
    import subprocess

    from cli_testing import CLI

    colour = (0.40, 0.25, 0.10)
    for space in ("rec709", "acescg"):
        out = tmp_path / f"ground_{space}.exr"
        args = ["sky", "--preset", "clear_day", "--width", WIDTH, "--method", "lut", "--sun-elevation", 40]
        args += ["--no-sun-disc", "--color-space", space, "--ground-color", ",".join(map(str, colour))]
        run = subprocess.run([CLI, *map(str, args), "-o", out], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        pixels, names = welkin.read_exr(str(out))[:2]  # channels in the file's (sorted) order
        got = pixels[..., [names.index(c) for c in "RGB"]]
        atm = welkin.Atmosphere.preset("clear_day")
        atm.ground_albedo = welkin.rgb_to_reflectance(colour, atm.wavelengths_nm, color_space=space)
        want = welkin.sky_image(atm, 0.0, SUN, WIDTH, method="lut", sun_disc=False, color_space=space)
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=0.0)
    bad = subprocess.run(
        [CLI, "sky", "--width", "16", "--ground-color", "0.4,1.5,0.1", "-o", str(tmp_path / "bad.exr")],
        capture_output=True,
        text=True,
    )
    assert bad.returncode != 0 and "--ground-color" in bad.stderr and "[0, 1]" in bad.stderr, bad.stderr
    assert not (tmp_path / "bad.exr").exists()
