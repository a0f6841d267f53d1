# SPDX-License-Identifier: Apache-2.0
"""The output colour spaces through the module and the CLI (color_space.hpp): each writes
the spectrum's XYZ through the space's matrix, so a Rec.2020 or ACEScg output is the
Rec.709 one times the published space-to-space matrix (nothing clamped on the way), and
bad names are refused naming color_space."""

import json
import subprocess

import numpy as np
import pytest

import welkin
from cli_testing import CLI

# Linear sRGB -> ACEScg (Bradford D65 -> ACES white), as the ACES OpenColorIO configs and
# colour-science publish it; and BT.2020 RGB -> XYZ (ITU-R BT.2087-0), with BT.709's.
REC709_TO_ACESCG = np.array(
    [[0.6130974, 0.3395231, 0.0473794], [0.0701937, 0.9163539, 0.0134523], [0.0206156, 0.1095698, 0.8698151]]
)
BT2020_TO_XYZ = np.array([[0.6370, 0.1446, 0.1689], [0.2627, 0.6780, 0.0593], [0.0, 0.0281, 1.0610]])
BT709_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
SPACES = ("rec709", "rec2020", "acescg")


def test_matrices_are_the_published_ones():
    np.testing.assert_allclose(welkin.color_space_matrix("rec709", "acescg"), REC709_TO_ACESCG, atol=3e-4)
    want = np.linalg.inv(BT2020_TO_XYZ) @ BT709_TO_XYZ
    np.testing.assert_allclose(welkin.color_space_matrix("rec709", "rec2020"), want, atol=5e-4)
    for a in SPACES:
        for b in SPACES:
            m = welkin.color_space_matrix(a, b)
            np.testing.assert_allclose(m @ np.ones(3), np.ones(3), atol=2e-4)  # white stays white
            np.testing.assert_allclose(welkin.color_space_matrix(b, a) @ m, np.eye(3), atol=1e-12)


def luminance(rgb, space):
    """Y of linear RGB in `space` (the Y row of its RGB -> XYZ)."""
    return np.asarray(rgb) @ np.linalg.inv(welkin.color_space_matrix("xyz", space))[1]


@pytest.mark.parametrize("space", ["rec2020", "acescg"])
def test_sky_image_and_sun_are_the_same_xyz(space):
    atm = welkin.Atmosphere.preset("hazy")
    sun_dir = [np.cos(np.radians(4.0)), 0.0, np.sin(np.radians(4.0))]
    m = welkin.color_space_matrix("rec709", space)
    # The sky (the 4-degree sun's disc is outside Rec.709: its colour is mapped as one).
    rec709 = welkin.sky_image(atm, 0.0, sun_dir, 64, "lut", sun_disc=False)
    other = welkin.sky_image(atm, 0.0, sun_dir, 64, "lut", sun_disc=False, color_space=space)
    # Inside both gamuts the same XYZ through each matrix; a colour outside one of them is
    # mapped into it (gamut.hpp: a channel at 0), keeping its luminance.
    inside = (rec709 > 0).all(axis=-1) & (other > 0).all(axis=-1)
    assert inside.mean() > 0.9
    np.testing.assert_allclose(
        other[inside], (rec709 @ m.T)[inside], rtol=2e-5, atol=1e-6 * np.abs(rec709).max()
    )
    np.testing.assert_allclose(
        luminance(other, space), luminance(rec709, "rec709"), rtol=1e-4, atol=1e-6 * np.abs(rec709).max()
    )
    high = [0.0, np.cos(np.radians(30.0)), np.sin(np.radians(30.0))]  # a sun inside every gamut
    s709, s = welkin.sun(atm, 0.0, high), welkin.sun(atm, 0.0, high, color_space=space)
    assert s.color_space == space and s709.color_space == "rec709"
    np.testing.assert_allclose(s.direct_irradiance_rgb, m @ s709.direct_irradiance_rgb, rtol=1e-9)
    # (The disc's centre radiance is not: each channel's limb profile is that channel's own
    # weighting of the wavelengths' profiles, so it depends on the basis; its integral over
    # the disc, the irradiance above, is linear in the spectrum.)


def test_spectrum_to_rgb_and_a_saturated_spectrum():
    # A band of 510-560 nm: a green outside Rec.709 (negative red there before the gamut
    # mapping, which brings it in at the same luminance), inside Rec.2020 and AP1 (every
    # channel positive, unmapped): a wider space keeps what Rec.709 cannot hold.
    wl = np.arange(400.0, 701.0, 5.0)
    band = ((wl >= 510) & (wl <= 560)).astype(np.float32)
    rgb = {s: welkin.spectrum_to_rgb(band, wl, color_space=s) for s in SPACES}
    assert (welkin.color_space_matrix("rec2020", "rec709") @ rgb["rec2020"])[0] < 0
    assert rgb["rec709"].min() >= 0 and rgb["rec709"].min() < 1e-6 * rgb["rec709"].max()
    assert (rgb["rec2020"] > 0).all() and (rgb["acescg"] > 0).all()
    np.testing.assert_allclose(
        rgb["acescg"], welkin.color_space_matrix("rec2020", "acescg") @ rgb["rec2020"], rtol=1e-5
    )
    np.testing.assert_allclose(
        luminance(rgb["rec709"], "rec709"), luminance(rgb["rec2020"], "rec2020"), rtol=1e-4
    )


def test_bad_color_space_is_refused():
    atm = welkin.Atmosphere.preset("clear")
    for call in (
        lambda: welkin.sun(atm, 0.0, [0, 0, 1], color_space="srgb"),
        lambda: welkin.sky_image(atm, 0.0, [0, 0, 1], 8, color_space="ACEScg"),
        lambda: welkin.color_space_matrix("rec709", "p3"),
    ):
        with pytest.raises(ValueError, match="color_space"):
            call()
    scene = {"version": 1, "color_space": "xyz"}
    with pytest.raises(ValueError, match="color_space"):
        welkin.SceneDescription.from_json_string(json.dumps(scene))


def test_scene_json_keeps_the_space():
    text = welkin.SceneDescription.from_json_string(json.dumps({"version": 1, "color_space": "acescg"}))
    assert json.loads(text.to_json_string())["color_space"] == "acescg"


def test_cli_sun_color_space():
    def sun(*extra):
        r = subprocess.run(
            [CLI, "sun", "--preset", "hazy", "--sun-elevation", "30", *extra],
            capture_output=True,
            text=True,
            check=True,
        )
        return json.loads(r.stdout)

    rec709, acescg = sun(), sun("--color-space", "acescg")
    assert acescg["color_space"] == "acescg"
    np.testing.assert_allclose(
        acescg["direct_irradiance_rgb_W_m2"],
        welkin.color_space_matrix("rec709", "acescg") @ rec709["direct_irradiance_rgb_W_m2"],
        rtol=1e-9,
    )
    r = subprocess.run([CLI, "sun", "--color-space", "srgb"], capture_output=True, text=True)
    assert r.returncode != 0 and "--color-space" in r.stderr


def test_sky_radiance_and_disc_image_take_the_space():
    atm = welkin.Atmosphere.preset("clear")
    sun_dir = [0.0, 0.5, 0.866]
    dirs = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.05]]) / np.array([[1.0], [np.hypot(1.0, 0.05)]])
    m = welkin.color_space_matrix("rec709", "rec2020")
    a = welkin.sky_radiance(atm, 0.0, sun_dir, dirs, "lut", "rgb")
    b = welkin.sky_radiance(atm, 0.0, sun_dir, dirs, "lut", "rgb", color_space="rec2020")
    np.testing.assert_allclose(b, a @ m.T, rtol=2e-5)
    d709 = welkin.sun_disc_image(atm, 0.0, sun_dir, 64)
    d2020 = welkin.sun_disc_image(atm, 0.0, sun_dir, 64, color_space="rec2020")
    np.testing.assert_allclose(d2020, d709 @ m.T, rtol=2e-5, atol=1e-6 * d709.max())
