# SPDX-License-Identifier: Apache-2.0
"""The add-on's Blender-free modules (addon/welkin/*.py, no bpy): loaded here as the
package `welkin_addon` (the add-on's own name, `welkin`, is the compiled module's in this
process) and driven with the module from build/."""

import dataclasses
import math
import pathlib
import sys

import numpy as np
import pytest

import welkin

ADDON = pathlib.Path(__file__).resolve().parents[2] / "addon" / "welkin"


from welkin_addon import native, pixels, sky_compute, sky_request  # noqa: E402 (conftest loads it)


def test_addon_package_imports_without_bpy():
    assert "bpy" not in sys.modules
    assert sys.modules["welkin_addon"].bl_info["version"] == tuple(
        int(x) for x in welkin.__version__.split(".")
    )


def test_native_missing_and_other_python(tmp_path):
    path, message = native.find(tmp_path)
    assert path is None and "missing" in message and "build_addon.sh" in message
    (tmp_path / "welkin.cpython-310-x86_64-linux-gnu.so").write_bytes(b"")
    path, message = native.find(tmp_path)
    assert path is None and "another Python" in message and "3.11" in message
    module, message = native.load(tmp_path)
    assert module is None and "another Python" in message


def test_native_finds_the_module_for_this_python():
    build = pathlib.Path(welkin.__file__).parent
    path, message = native.find(build)
    assert message is None and path == pathlib.Path(welkin.__file__)


def test_request_validation_names_the_parameter():
    good = sky_request.SkyRequest(width=256)
    sky_request.validate(good, welkin)
    for change, parameter in (
        ({"preset": "venus"}, "preset"),
        ({"width": 300}, "width"),
        ({"air_density": -1.0}, "air_density"),
        ({"exposure": 0.0}, "exposure"),
        ({"altitude_m": -5.0}, "altitude_m"),
        ({"ground_albedo": 1.5}, "ground_albedo"),
        ({"ground_color": (0.2, 1.5, 0.1)}, "ground_color"),
        ({"ground_color": (0.2, 0.1)}, "ground_color"),
        ({"ground_color": (0.2, math.nan, 0.1)}, "ground_color"),
        ({"sun_direction": (0.0, 0.0, 0.0)}, "sun_direction"),
        ({"method": "reference"}, "method"),
    ):
        with pytest.raises(ValueError, match=parameter):
            sky_request.validate(dataclasses.replace(good, **change), welkin)


def test_auto_method_falls_back_to_lut_without_the_modules_own():
    expected = "auto" if "auto" in welkin.methods() else "lut"
    assert sky_request.resolve_method("auto", welkin) == expected
    assert sky_request.resolve_method("analytic", welkin) == "analytic"


def test_atmosphere_multipliers_scale_the_presets_coefficients():
    base = welkin.Atmosphere.preset("hazy")
    req = sky_request.SkyRequest(
        preset="hazy", air_density=2.0, aerosol_density=0.5, ozone_density=0.0, ground_albedo=0.3
    )
    atm = sky_request.build_atmosphere(req, welkin)
    np.testing.assert_allclose(atm.rayleigh_scattering, 2.0 * base.rayleigh_scattering)
    np.testing.assert_allclose(atm.mie_scattering, 0.5 * base.mie_scattering)
    np.testing.assert_allclose(atm.mie_extinction, 0.5 * base.mie_extinction)
    np.testing.assert_allclose(atm.absorption_extinction, 0.0)
    np.testing.assert_allclose(atm.ground_albedo, 0.3)


def test_ground_color_becomes_the_cores_reflectance_spectrum():
    # The request's colour is the core's rgb_to_reflectance of it, in the request's colour
    # space, at the atmosphere's wavelengths (default four and spectral alike), and wins
    # over a grey ground_albedo; its colour comes back through the core's inverse.
    for spectral in (False, True):
        for space in ("rec709", "acescg"):
            req = sky_request.SkyRequest(
                ground_color=(0.4, 0.25, 0.1), ground_albedo=0.3, spectral=spectral, color_space=space
            )
            atm = sky_request.build_atmosphere(req, welkin)
            w = atm.wavelengths_nm
            np.testing.assert_allclose(
                atm.ground_albedo, welkin.rgb_to_reflectance((0.4, 0.25, 0.1), w, color_space=space)
            )
            if spectral:
                rgb = welkin.reflectance_to_rgb(atm.ground_albedo, w, color_space=space)
                np.testing.assert_allclose(rgb, (0.4, 0.25, 0.1), atol=2e-3)
    a = sky_request.SkyRequest(ground_color=(0.4, 0.25, 0.1))
    assert a.key() != dataclasses.replace(a, ground_color=(0.4, 0.25, 0.11)).key()
    assert a.key() != dataclasses.replace(a, ground_color=()).key()


def test_observer_altitude_below_the_ground_is_put_on_it():
    assert sky_request.observer_altitude(100.0, 20.0) == (120.0, None)
    altitude, warning = sky_request.observer_altitude(10.0, -30.0)
    assert altitude == 0.0 and "20 m below the ground" in warning


def test_key_follows_the_sun_and_the_settings():
    a = sky_request.SkyRequest(sun_direction=(0.0, 0.6, 0.8))
    assert a.key() == dataclasses.replace(a, sun_direction=(0.0, 0.6, 0.8 + 1e-12)).key()
    assert a.key() != dataclasses.replace(a, sun_direction=(0.0, 0.61, 0.8)).key()
    assert a.key() != dataclasses.replace(a, exposure=2.0).key()


def disc_energy(model):
    """The integral of the DiscModel's radiance over its solid angle, per channel. With
    s = sin rho / sin alpha and mu = sqrt(1 - s^2): dOmega = 2 pi sin rho d rho
    = 2 pi sin^2 alpha s ds / cos rho and s ds = -mu dmu, so the integral is
    2 pi sin^2 alpha int_0^1 L(mu) mu / cos rho dmu, cos rho = sqrt(1 - (1 - mu^2) sin^2 alpha):
    a polynomial times a smooth weight, which 40-point Gauss-Legendre integrates exactly."""
    x, w = np.polynomial.legendre.leggauss(40)
    mu = 0.5 * (x + 1.0)
    sin2 = math.sin(model.radius_rad) ** 2
    weight = 0.5 * w * mu / np.sqrt(1.0 - (1.0 - mu * mu) * sin2)
    radiance = np.polynomial.polynomial.polyval(mu, model.coefficients).T  # (n, 3)
    return 2.0 * math.pi * sin2 * (weight[:, None] * radiance).sum(axis=0)


@pytest.fixture
def addon_atm():
    """The add-on's atmosphere for the default request: the preset at the library's default
    wavelengths (not conftest's 680/550/440 nm)."""
    return welkin.Atmosphere.preset(sky_request.SkyRequest().preset)


def test_compute_is_the_modules_sky_disc_and_sun(addon_atm, sun_direction):
    atm = addon_atm
    req = sky_request.SkyRequest(
        sun_direction=tuple(sun_direction), width=256, exposure=0.5, altitude_m=250.0
    )
    result = sky_compute.compute(welkin, req)
    np.testing.assert_array_equal(
        result.sky,
        welkin.sky_image(atm, 250.0, sun_direction, 256, result.method, sun_disc=False, exposure=0.5),
    )
    rgb = 0.5 * np.asarray(welkin.sun(atm, 250.0, sun_direction).direct_irradiance_rgb)
    # The disc the world's nodes draw: the sun's direction and radius, the horizon of the
    # observer 250 m up, and the direct irradiance as its integral over the disc (to 1e-4:
    # Neckel & Labs' rows of a_k, which the core's polynomial carries, sum to 1 within
    # 2e-5, e.g. 0.99998 at 428 and 444 nm).
    disc = result.disc
    s = np.asarray(sun_direction, dtype=float)
    np.testing.assert_allclose(disc.direction, s / np.linalg.norm(s), rtol=1e-12)
    assert disc.radius_rad == atm.sun_angular_radius_rad
    r, radius = atm.bottom_radius_m + 250.0, atm.bottom_radius_m
    assert disc.horizon_z == pytest.approx(-math.sqrt(r * r - radius * radius) / r, rel=1e-9)
    np.testing.assert_allclose(disc_energy(disc), rgb, rtol=1e-4)
    # Limb-darkened: the centre brighter than the mean (Neckel & Labs: by 1.2-1.4 in the
    # visible).
    centre = disc.coefficients.sum(axis=0)
    mean = rgb / (2.0 * math.pi * (1.0 - math.cos(disc.radius_rad)))
    assert np.all(centre / mean > 1.15), centre / mean
    np.testing.assert_allclose(np.array(result.lamp.color) * result.lamp.strength_w_m2, rgb, rtol=1e-12)
    assert max(result.lamp.color) == 1.0
    assert result.lamp.angle_rad == pytest.approx(2 * atm.sun_angular_radius_rad)
    assert result.warnings == []


def test_spectral_colour_is_the_48_wavelength_sky():
    """Colour > Spectral: the sky, disc and lamp of the preset at 360..830 nm (48
    wavelengths), a different request key, and in twilight the colour the default's fitted
    conversion approximates (CIE xy of the hemisphere's mean within 0.005)."""
    e = math.radians(-4.0)
    sun = (math.cos(e), 0.0, math.sin(e))
    fast = sky_request.SkyRequest(sun_direction=sun, width=256, method="lut")
    exact = sky_request.SkyRequest(sun_direction=sun, width=256, method="lut", spectral=True)
    assert fast.key() != exact.key()
    atm = sky_request.build_atmosphere(exact, welkin)
    assert len(atm.wavelengths_nm) == 48
    result = sky_compute.compute(welkin, exact)
    np.testing.assert_array_equal(
        result.sky, welkin.sky_image(atm, 0.0, sun, 256, result.method, sun_disc=False)
    )

    def xy(image):
        rgb = image[: image.shape[0] // 2].reshape(-1, 3).mean(axis=0)  # upper hemisphere
        m = np.array(
            [
                [0.4124564, 0.3575761, 0.1804375],
                [0.2126729, 0.7151522, 0.0721750],
                [0.0193339, 0.1191920, 0.9503041],
            ]
        )
        x = m @ rgb
        return x[:2] / x.sum()

    fast_sky = sky_compute.compute(welkin, fast).sky
    assert np.linalg.norm(xy(fast_sky) - xy(result.sky)) < 0.005
    assert not np.array_equal(fast_sky, result.sky)


def test_sun_below_the_horizon_turns_the_lamp_off_with_a_warning():
    e = math.radians(-5.0)
    req = sky_request.SkyRequest(sun_direction=(math.cos(e), 0.0, math.sin(e)), width=256)
    result = sky_compute.compute(welkin, req)
    assert result.lamp.strength_w_m2 == 0.0
    assert any("5.0 degrees below the horizon" in w for w in result.warnings)
    assert np.all(np.isfinite(result.sky)) and result.sky.max() > 0.0
    assert result.disc is None


def test_blender_pixels_are_bottom_row_first_rgba():
    img = np.arange(2 * 3 * 3, dtype=np.float32).reshape(2, 3, 3)
    flat = pixels.to_blender(img)
    assert flat.shape == (2 * 3 * 4,)
    np.testing.assert_array_equal(flat[:3], img[1, 0])  # Blender's first pixel: bottom left
    np.testing.assert_array_equal(flat.reshape(2, 3, 4)[..., 3], 1.0)
    np.testing.assert_array_equal(pixels.from_blender(flat, 3, 2), img)


def test_pixels_written_into_a_kept_buffer():
    b = np.zeros((2, 4, 3), np.float32)
    b[1, 3] = (4.0, 5.0, 6.0)
    out = pixels.rgba_buffer(4, 2)
    np.testing.assert_array_equal(pixels.to_blender(b, out), pixels.to_blender(b))


def test_aerosol_optical_depth_and_turbidity_set_the_column():
    """The panel's Aerosol Amount: an optical depth at 550 nm, or Preetham's turbidity
    (converted by the core), sets the preset's aerosol column; the multiplier scales it."""
    atm = sky_request.build_atmosphere(sky_request.SkyRequest(aerosol_optical_depth=0.3), welkin)
    assert atm.aerosol_optical_depth() == pytest.approx(0.3, rel=1e-9)
    atm = sky_request.build_atmosphere(
        sky_request.SkyRequest(aerosol_optical_depth=0.3, aerosol_density=2.0), welkin
    )
    assert atm.aerosol_optical_depth() == pytest.approx(0.6, rel=1e-9)
    atm = sky_request.build_atmosphere(sky_request.SkyRequest(turbidity=3.0), welkin)
    want = welkin.preetham_turbidity_to_aerosol_optical_depth(3.0)
    assert atm.aerosol_optical_depth() == pytest.approx(want, rel=1e-9)
    assert 0.18 < want < 0.22
    for bad, name in (
        (dict(aerosol_optical_depth=11.0), "aerosol_optical_depth"),
        (dict(aerosol_optical_depth=math.nan), "aerosol_optical_depth"),
        (dict(turbidity=0.5), "turbidity"),
    ):
        with pytest.raises(ValueError, match=name):
            sky_request.validate(sky_request.SkyRequest(**bad), welkin)
