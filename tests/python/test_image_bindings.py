# SPDX-License-Identifier: Apache-2.0
"""welkin.sky_image, sun_disc_image, write_exr, read_exr: the thin bindings of the core's
equirect sky images and EXR I/O. Tolerances: float32 rounding (1e-5 relative) where two
paths compute the same numbers; the disc's energy to 1e-4 (the core makes it exact, the
sum here is in float64 over float32 pixels)."""

import math

import numpy as np
import pytest

import welkin


def solid_angles(width, height):
    rows = np.arange(height)
    return (2 * math.pi / width) * (
        np.sin(math.pi * (0.5 - rows / height)) - np.sin(math.pi * (0.5 - (rows + 1) / height))
    )


def test_sky_image_is_sky_radiance_over_the_pixel_directions(atm, sun_direction):
    img = welkin.sky_image(atm, 100.0, sun_direction, 64, sun_disc=False, ground=False)
    assert img.shape == (32, 64, 3) and img.dtype == np.float32
    dirs = welkin.equirect_pixel_directions(64, 32).reshape(-1, 3)
    ref = welkin.sky_radiance(atm, 100.0, sun_direction, dirs, output="rgb").reshape(32, 64, 3)
    np.testing.assert_allclose(img, ref, rtol=1e-5)


def test_disc_image_is_the_difference_and_delivers_the_direct_irradiance(atm, sun_direction):
    with_disc = welkin.sky_image(atm, 0.0, sun_direction, 128)
    without = welkin.sky_image(atm, 0.0, sun_direction, 128, sun_disc=False)
    disc = welkin.sun_disc_image(atm, 0.0, sun_direction, 128)
    np.testing.assert_allclose(with_disc, without + disc, rtol=1e-5, atol=1e-6)
    assert np.count_nonzero(disc.sum(axis=2)) > 0
    energy = (disc.astype(np.float64) * solid_angles(128, 64)[:, None, None]).sum(axis=(0, 1))
    expected = welkin.sun(atm, 0.0, sun_direction).direct_irradiance_rgb
    np.testing.assert_allclose(energy, expected, rtol=1e-4)


def test_exposure_scales_everything(atm, sun_direction):
    a = welkin.sky_image(atm, 0.0, sun_direction, 32)
    b = welkin.sky_image(atm, 0.0, sun_direction, 32, exposure=0.25)
    np.testing.assert_allclose(b, 0.25 * a, rtol=1e-6)


def test_spectral_output_has_one_channel_per_wavelength(atm, sun_direction):
    img = welkin.sky_image(atm, 0.0, sun_direction, 16, output="spectral")
    assert img.shape == (8, 16, len(atm.wavelengths_nm))


@pytest.mark.parametrize(
    "kwargs, parameter",
    [
        ({"width": 7}, "width"),
        ({"width": 2}, "width"),
        ({"method": "nope"}, "method"),
        ({"output": "xyz"}, "output"),
        ({"exposure": 0.0}, "exposure"),
        ({"altitude_m": -1.0}, "altitude"),
        ({"sun_direction": (0, 0, 0)}, "sun_direction"),
    ],
)
def test_sky_image_bad_input_names_the_parameter(atm, sun_direction, kwargs, parameter):
    args = {"atmosphere": atm, "altitude_m": 0.0, "sun_direction": sun_direction, "width": 16}
    args.update(kwargs)
    with pytest.raises(ValueError, match=parameter):
        welkin.sky_image(**args)


def test_exr_round_trip_and_no_overwrite(tmp_path, atm, sun_direction):
    img = welkin.sky_image(atm, 0.0, sun_direction, 32)
    path = tmp_path / "sky.exr"
    assert welkin.write_exr(str(path), img) == 0
    pixels, names = welkin.read_exr(str(path))
    back = np.stack([pixels[..., names.index(c)] for c in "RGB"], axis=-1)
    np.testing.assert_array_equal(back, img)
    before = path.read_bytes()
    with pytest.raises(OSError, match="exists"):
        welkin.write_exr(str(path), img * 2)
    assert path.read_bytes() == before
    clamped = welkin.write_exr(str(path), img, half=True, overwrite=True)
    assert clamped == np.count_nonzero(img > 65504.0)


def test_write_exr_checks_channel_names(tmp_path):
    with pytest.raises(ValueError, match="channel_names"):
        welkin.write_exr(str(tmp_path / "a.exr"), np.zeros((2, 2, 5), np.float32))
    with pytest.raises(ValueError, match="channel_names"):
        welkin.write_exr(str(tmp_path / "a.exr"), np.zeros((2, 2, 2), np.float32), ["A"])
    welkin.write_exr(str(tmp_path / "a.exr"), np.zeros((2, 2, 2), np.float32), ["Y", "Z"])
