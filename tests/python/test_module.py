# SPDX-License-Identifier: Apache-2.0
"""Tests of the `welkin` Python module: the bindings' contract, not the physics.

What the module promises (src/python/): the documented call works and returns arrays
of the right shape, dtype and units; every bad input raises ValueError (or OSError for
files) naming the parameter; JSON round-trips exactly; long computations release the GIL
and can be cancelled; input buffers are read in place or converted, never modified, and
outputs never alias them. Numbers are checked against closed forms where the bindings
pass a core result through (sun transmittance, equirect mapping, density profiles).

Deterministic plumbing tests use method="reference" with few paths and a fixed seed
(the same seed gives the same numbers, so two calls can be compared exactly).
"""

import _thread
import copy
import json
import pathlib
import pickle
import re
import threading
import time

import numpy as np
import pytest

import welkin

FEW_PATHS = dict(method="reference", paths=16, seed=3)


def radiance(atm, sun_direction, dirs, **kw):
    args = dict(FEW_PATHS)
    args.update(kw)
    return welkin.sky_radiance(atm, altitude_m=0.0, sun_direction=sun_direction, view_directions=dirs, **args)


# --- the documented call --------------------------------------------------------------


@pytest.mark.parametrize("output, columns", [("spectral", 3), ("rgb", 3)])
def test_documented_call_shapes_and_dtype(atm, sun_direction, view_directions, output, columns):
    L = welkin.sky_radiance(
        atm,
        altitude_m=0.0,
        sun_direction=sun_direction,
        view_directions=view_directions,
        method="lut",
        output=output,
    )
    assert isinstance(L, np.ndarray)
    assert L.dtype == np.float32
    assert L.shape == (len(view_directions), columns)
    assert L.flags.c_contiguous and L.flags.owndata and L.flags.writeable
    assert np.all(np.isfinite(L))
    assert np.all(L >= 0.0)
    # Daylight sky at the zenith is bright, not zero, in every channel.
    assert np.all(L[0] > 0.0)


@pytest.mark.parametrize("method", welkin.methods())
def test_every_method_runs_and_is_finite(atm, sun_direction, view_directions, method):
    L = welkin.sky_radiance(atm, 0.0, sun_direction, view_directions, method, "spectral", paths=16, steps=16)
    assert L.shape == (len(view_directions), atm.channels)
    assert np.all(np.isfinite(L)) and np.all(L >= 0.0)


def test_spectral_wavelengths_give_one_column_each(sun_direction, view_directions):
    w = welkin.spectral_wavelengths_nm()
    atm = welkin.Atmosphere.preset("bruneton2017", wavelengths_nm=w)
    L = radiance(atm, sun_direction, view_directions)
    assert L.shape == (len(view_directions), len(w))
    rgb = radiance(atm, sun_direction, view_directions, output="rgb")
    assert rgb.shape == (len(view_directions), 3)


def test_rgb_output_is_the_documented_conversion_of_the_spectral_output(atm, sun_direction, view_directions):
    spectral = radiance(atm, sun_direction, view_directions)
    rgb = radiance(atm, sun_direction, view_directions, output="rgb")
    expected = welkin.spectrum_to_rgb(spectral, atm.wavelengths_nm, lambda_power=-3)
    np.testing.assert_allclose(rgb, expected, rtol=1e-6, atol=0)


def test_return_standard_error(atm, sun_direction, view_directions):
    L, se = radiance(atm, sun_direction, view_directions, return_standard_error=True)
    assert L.shape == se.shape == (len(view_directions), atm.channels)
    assert se.dtype == np.float32
    assert np.all(np.isfinite(se)) and np.all(se >= 0.0)
    assert not np.shares_memory(L, se)
    # Without the flag: the same radiance, alone.
    L2 = radiance(atm, sun_direction, view_directions)
    np.testing.assert_array_equal(L, L2)


def test_deterministic_methods_report_zero_standard_error(atm, sun_direction, view_directions):
    _, se = welkin.sky_radiance(atm, 0.0, sun_direction, view_directions, "lut", return_standard_error=True)
    np.testing.assert_array_equal(se, 0.0)


def test_no_directions_give_an_empty_result(atm, sun_direction):
    L = radiance(atm, sun_direction, np.zeros((0, 3)))
    assert L.shape == (0, 3) and L.dtype == np.float32


# --- input buffers: in place or converted, never modified, never aliased ----------------


def _misaligned(a):
    """A C-contiguous float64 copy of `a` whose buffer starts at an odd byte address."""
    raw = bytearray(a.nbytes + 1)
    m = np.frombuffer(raw, dtype=np.float64, count=a.size, offset=1).reshape(a.shape)
    m[...] = a
    assert not m.flags.aligned and m.flags.c_contiguous
    return m


def test_any_array_like_gives_the_same_answer(atm, sun_direction, view_directions):
    expected = radiance(atm, sun_direction, view_directions)
    bigger = np.zeros((2 * len(view_directions), 3))
    bigger[::2] = view_directions
    variants = {
        "fortran order": np.asfortranarray(view_directions),
        "strided rows": bigger[::2],
        "transposed view": np.ascontiguousarray(view_directions.T).T,
        "list of tuples": [tuple(d) for d in view_directions],
        "misaligned buffer": _misaligned(view_directions),
    }
    for name, dirs in variants.items():
        if isinstance(dirs, np.ndarray) and name != "misaligned buffer":
            assert not dirs.flags.c_contiguous, name
        np.testing.assert_array_equal(radiance(atm, sun_direction, dirs), expected, err_msg=name)


def test_float32_directions_are_converted(atm, sun_direction, view_directions):
    d32 = view_directions.astype(np.float32)
    np.testing.assert_array_equal(
        radiance(atm, sun_direction, d32), radiance(atm, sun_direction, d32.astype(np.float64))
    )


def test_inputs_are_not_modified_and_outputs_not_aliased(atm, sun_direction, view_directions):
    before = view_directions.copy()
    L1 = radiance(atm, sun_direction, view_directions)
    L2 = radiance(atm, sun_direction, view_directions)
    np.testing.assert_array_equal(view_directions, before)
    assert not np.shares_memory(L1, L2)
    assert not np.shares_memory(L1, view_directions)
    L1[...] = -1.0
    assert np.all(L2 >= 0.0)
    np.testing.assert_array_equal(L2, radiance(atm, sun_direction, view_directions))


def test_the_atmosphere_is_not_modified(atm, sun_direction, view_directions):
    before = atm.to_json_string()
    radiance(atm, sun_direction, view_directions)
    assert atm.to_json_string() == before


# --- bad input: ValueError naming the parameter -----------------------------------------


def _raises_naming(exc, parameter, fn, *args, **kwargs):
    with pytest.raises(exc) as info:
        fn(*args, **kwargs)
    assert parameter in str(info.value), f"{parameter!r} not in {str(info.value)!r}"
    return info.value


def test_unknown_preset():
    _raises_naming(ValueError, "preset", welkin.Atmosphere.preset, "venus")


def test_preset_wavelength_out_of_range():
    _raises_naming(
        ValueError,
        "wavelengths_nm[1]",
        welkin.Atmosphere.preset,
        "clear",
        wavelengths_nm=[550.0, 100.0, 440.0],
    )


def test_unknown_method(atm, sun_direction, view_directions):
    e = _raises_naming(ValueError, "method", radiance, atm, sun_direction, view_directions, method="magic")
    assert "reference" in str(e)  # the message lists the accepted names


def test_unknown_output(atm, sun_direction, view_directions):
    _raises_naming(ValueError, "output", radiance, atm, sun_direction, view_directions, output="xyz")


@pytest.mark.parametrize("bad", [(0.0, 0.0, 0.0), (np.nan, 0.0, 1.0), (np.inf, 0.0, 0.0)])
def test_bad_view_direction_is_named_by_index(atm, sun_direction, view_directions, bad):
    dirs = view_directions.copy()
    dirs[5] = bad
    _raises_naming(ValueError, "view_directions[5]", radiance, atm, sun_direction, dirs)


@pytest.mark.parametrize(
    "dirs",
    [
        np.zeros((4, 2)),  # not 3 columns
        np.zeros(3),  # one direction without the N axis
        np.zeros((2, 4, 3)),  # too many axes
        np.float64(1.0),  # a scalar
        [[0.0, 0.0, 1.0], [1.0]],  # ragged
        [["a", "b", "c"]],  # not numbers
    ],
)
def test_view_directions_of_the_wrong_shape(atm, sun_direction, dirs):
    _raises_naming(ValueError, "view_directions", radiance, atm, sun_direction, dirs)


@pytest.mark.parametrize("sun", [(0.0, 0.0, 0.0), (np.nan, 0.0, 1.0), (0.0, 1.0), "up"])
def test_bad_sun_direction(atm, view_directions, sun):
    _raises_naming(ValueError, "sun_direction", radiance, atm, sun, view_directions)


@pytest.mark.parametrize("altitude", [-1.0, np.nan, np.inf])
def test_bad_altitude(atm, sun_direction, view_directions, altitude):
    _raises_naming(
        ValueError,
        "altitude_m",
        welkin.sky_radiance,
        atm,
        altitude,
        sun_direction,
        view_directions,
        **FEW_PATHS,
    )


@pytest.mark.parametrize(
    "option, value, parameter",
    [
        ("steps", 0, "raymarch_steps"),
        ("sun_steps", 0, "raymarch_sun_steps"),
        ("paths", 0, "reference_paths"),
        ("skyview_width", 1, "skyview_width"),
        ("transmittance_height", 100000, "transmittance_height"),
    ],
)
def test_bad_options(atm, sun_direction, view_directions, option, value, parameter):
    _raises_naming(ValueError, parameter, radiance, atm, sun_direction, view_directions, **{option: value})


def test_standard_error_needs_spectral_output(atm, sun_direction, view_directions):
    _raises_naming(
        ValueError,
        "return_standard_error",
        radiance,
        atm,
        sun_direction,
        view_directions,
        output="rgb",
        return_standard_error=True,
    )


def test_progress_must_be_callable(atm, sun_direction, view_directions):
    _raises_naming(TypeError, "progress", radiance, atm, sun_direction, view_directions, progress=42)


def test_an_invalid_atmosphere_is_refused_before_computing(atm, sun_direction, view_directions):
    atm.solar_irradiance = [1.0, 2.0]  # 2 values for 3 wavelengths
    _raises_naming(ValueError, "solar_irradiance", atm.validate)
    _raises_naming(ValueError, "solar_irradiance", radiance, atm, sun_direction, view_directions)


# --- cancellation and the GIL -----------------------------------------------------------

# Enough work that no implementation finishes it in the moments the tests need.
LONG_WORK = dict(method="reference", paths=1_000_000, seed=1)
LONG_DIRECTIONS = np.tile([[0.0, 0.6, 0.8]], (512, 1))


def test_progress_reports_fractions_up_to_one(atm, sun_direction, view_directions):
    seen = []
    radiance(atm, sun_direction, view_directions, progress=seen.append)
    assert seen, "the progress callback was never called"
    assert all(0.0 <= f <= 1.0 for f in seen)
    assert seen == sorted(seen)
    assert seen[-1] == 1.0


def test_progress_returning_false_cancels_with_keyboard_interrupt(atm, sun_direction):
    seen = []

    def stop(fraction):
        seen.append(fraction)
        return False

    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        welkin.sky_radiance(atm, 0.0, sun_direction, LONG_DIRECTIONS, progress=stop, **LONG_WORK)
    assert len(seen) == 1 and seen[0] < 1.0  # asked once, stopped there
    assert time.monotonic() - start < 60.0


def test_an_exception_in_the_progress_callback_propagates(atm, sun_direction):
    class Stop(Exception):
        pass

    def fail(fraction):
        raise Stop(fraction)

    with pytest.raises(Stop):
        welkin.sky_radiance(atm, 0.0, sun_direction, LONG_DIRECTIONS, progress=fail, **LONG_WORK)


def test_ctrl_c_cancels_a_long_computation(atm, sun_direction):
    """SIGINT arriving while the core computes (the main thread waiting in C++) stops it.

    The progress callback is a C function (list.append), so no Python code runs during
    the call that could notice the signal instead of the module."""
    seen = []
    timer = threading.Timer(0.2, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            welkin.sky_radiance(atm, 0.0, sun_direction, LONG_DIRECTIONS, progress=seen.append, **LONG_WORK)
    finally:
        timer.cancel()
        timer.join()
    elapsed = time.monotonic() - start
    assert seen and max(seen) < 1.0, "the computation ran to the end instead of stopping"
    assert elapsed < 60.0


def test_the_gil_is_released_while_computing(atm, sun_direction):
    """Another Python thread keeps running while the core computes (no callback given)."""
    ticks = []
    finished = threading.Event()

    def ticker():
        while not finished.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.001)

    thread = threading.Thread(target=ticker)
    thread.start()
    try:
        # Grow the work until one call lasts long enough to tell (>= 50 ms).
        paths = 1000
        while True:
            start = time.monotonic()
            radiance(atm, sun_direction, LONG_DIRECTIONS[:64], paths=paths)
            end = time.monotonic()
            if end - start >= 0.05 or paths >= 1 << 24:
                break
            paths *= 4
    finally:
        finished.set()
        thread.join()
    assert end - start >= 0.05, "too little work to tell"
    during = [t for t in ticks if start < t < end]
    # With the GIL held for the whole call the other thread could not tick at all.
    assert len(during) >= 5, f"{len(during)} ticks in {end - start:.3f} s"


# --- Atmosphere ---------------------------------------------------------------------------


def test_preset_names_and_methods():
    names = welkin.Atmosphere.preset_names()
    assert set(names) == {
        "clear_day",
        "clear",
        "hazy",
        "polluted",
        "desert_dust",
        "maritime",
        "bruneton2017",
        "mars",
    }
    assert names[0] == "clear_day"  # the default, an ordinary clear day
    # Its aerosol: an optical depth at 550 nm of a clear day (0.08-0.15), the others theirs.
    assert 0.08 <= welkin.Atmosphere.preset(names[0]).aerosol_optical_depth() <= 0.15
    hazy = welkin.Atmosphere.preset("hazy", welkin.spectral_wavelengths_nm())  # 550 nm a channel
    assert hazy.aerosol_optical_depth(550.0) == pytest.approx(0.327)
    assert welkin.preetham_turbidity_to_aerosol_optical_depth(2.0) == pytest.approx(0.1007, abs=1e-3)
    assert welkin.methods() == ["analytic", "lut", "raymarch", "reference", "auto"]
    for name in welkin.Atmosphere.preset_names():
        a = welkin.Atmosphere.preset(name)
        a.validate()
        assert a.name == name


def test_atmosphere_attributes(atm):
    np.testing.assert_array_equal(atm.wavelengths_nm, [680.0, 550.0, 440.0])
    assert atm.channels == 3
    assert atm.bottom_radius_m == 6360e3 and atm.top_radius_m == 6420e3
    assert atm.atmosphere_thickness_m == 60e3
    assert atm.mie_g == 0.8 and atm.mie_phase == "cornette_shanks"
    np.testing.assert_array_equal(atm.ground_albedo, [0.1, 0.1, 0.1])
    for name in (
        "wavelengths_nm",
        "solar_irradiance",
        "rayleigh_scattering",
        "mie_scattering",
        "mie_extinction",
        "absorption_extinction",
        "ground_albedo",
    ):
        value = getattr(atm, name)
        assert value.dtype == np.float64 and value.shape == (3,), name
        with pytest.raises(ValueError):  # read-only copy: edits must not vanish silently
            value[0] = 1.0


def test_atmosphere_attributes_are_writable_and_validated(atm):
    atm.mie_g = 0.5
    atm.ground_albedo = [0.2, 0.3, 0.4]
    atm.mie_phase = "henyey_greenstein"
    atm.name = "mine"
    atm.rayleigh_density = welkin.DensityProfile.exponential(7000.0)
    atm.validate()
    assert atm.mie_g == 0.5 and atm.mie_phase == "henyey_greenstein" and atm.name == "mine"
    np.testing.assert_array_equal(atm.ground_albedo, [0.2, 0.3, 0.4])
    assert atm.rayleigh_density.exponential_scale_height_m == pytest.approx(7000.0)

    atm.mie_g = 1.5
    _raises_naming(ValueError, "mie.g", atm.validate)
    atm.mie_g = 0.8
    atm.ground_albedo = [0.1, 2.0, 0.1]
    _raises_naming(ValueError, "ground_albedo[1]", atm.validate)
    _raises_naming(ValueError, "mie_phase", setattr, atm, "mie_phase", "rayleigh")
    _raises_naming(ValueError, "solar_irradiance", setattr, atm, "solar_irradiance", [[1.0]])


def test_extinction_and_scattering_at_the_ground(atm):
    # At h = 0: Rayleigh and Mie densities are 1, the ozone tent is 0.
    np.testing.assert_allclose(atm.extinction(0.0), atm.rayleigh_scattering + atm.mie_extinction, rtol=1e-15)
    np.testing.assert_allclose(atm.scattering(0.0), atm.rayleigh_scattering + atm.mie_scattering, rtol=1e-15)
    # At the ozone peak (25 km) every term contributes.
    h = 25e3
    expected = (
        atm.rayleigh_scattering * np.exp(-h / 8000.0)
        + atm.mie_extinction * np.exp(-h / 1200.0)
        + atm.absorption_extinction
    )
    np.testing.assert_allclose(atm.extinction(h), expected, rtol=1e-12)


def test_density_profiles():
    p = welkin.DensityProfile.exponential(8000.0)
    assert p.density(8000.0) == pytest.approx(np.exp(-1.0), rel=1e-15)
    h = np.array([[0.0, 4000.0], [8000.0, 16000.0]])
    np.testing.assert_allclose(p.density(h), np.exp(-h / 8000.0), rtol=1e-15)
    tent = welkin.DensityProfile.tent(10e3, 25e3, 40e3)
    np.testing.assert_allclose(
        tent.density(np.array([5e3, 10e3, 17.5e3, 25e3, 32.5e3, 45e3])),
        [0.0, 0.0, 0.5, 1.0, 0.5, 0.0],
        atol=1e-12,
    )
    assert tent.exponential_scale_height_m is None
    layers = [welkin.DensityLayer(width_m=1000.0, constant=1.0), welkin.DensityLayer()]
    step = welkin.DensityProfile(layers)
    np.testing.assert_array_equal(step.density(np.array([500.0, 1500.0])), [1.0, 0.0])
    assert len(step.layers) == 2 and step.layers[0].width_m == 1000.0
    _raises_naming(ValueError, "scale_height_m", welkin.DensityProfile.exponential, -1.0)


def test_copy_and_pickle_are_independent(atm):
    for other in (atm.copy(), copy.copy(atm), copy.deepcopy(atm), pickle.loads(pickle.dumps(atm))):
        assert other.to_json_string() == atm.to_json_string()
        other.mie_g = 0.1
        assert atm.mie_g == 0.8


# --- JSON ---------------------------------------------------------------------------------


def test_json_round_trip_is_exact(tmp_path):
    a = welkin.Atmosphere.preset("mars", wavelengths_nm=[700.0, 600.0, 500.0, 400.0])
    a.mie_g = 0.123456789012345
    a.name = "round trip"
    path = tmp_path / "mars.json"
    a.to_json(path)
    b = welkin.Atmosphere.from_json(path)
    assert b.to_json_string() == a.to_json_string()
    assert b.mie_g == a.mie_g and b.name == "round trip"
    np.testing.assert_array_equal(b.wavelengths_nm, a.wavelengths_nm)
    np.testing.assert_array_equal(b.mie_scattering, a.mie_scattering)
    # str paths work as well as pathlib ones.
    c = welkin.Atmosphere.from_json(str(path))
    assert c.to_json_string() == a.to_json_string()


def test_json_preset_with_overrides(tmp_path):
    path = tmp_path / "hazy.json"
    path.write_text(json.dumps({"preset": "hazy", "mie": {"g": 0.75}, "ground_albedo": 0.3}))
    a = welkin.Atmosphere.from_json(path)
    hazy = welkin.Atmosphere.preset("hazy")
    assert a.mie_g == 0.75
    np.testing.assert_array_equal(a.ground_albedo, [0.3] * a.channels)
    np.testing.assert_array_equal(a.mie_scattering, hazy.mie_scattering)


def test_to_json_refuses_to_overwrite(atm, tmp_path):
    path = tmp_path / "sky.json"
    path.write_text("precious")
    _raises_naming(OSError, str(path), atm.to_json, path)
    assert path.read_text() == "precious"
    atm.to_json(path, overwrite=True)
    assert welkin.Atmosphere.from_json(path).to_json_string() == atm.to_json_string()


def test_to_json_unwritable_path(atm, tmp_path):
    path = tmp_path / "no such folder" / "sky.json"
    _raises_naming(OSError, str(path), atm.to_json, path)
    assert not path.parent.exists()


def test_malformed_json_file(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"preset": "clear", ')
    e = _raises_naming(ValueError, str(path), welkin.Atmosphere.from_json, path)
    assert "malformed" in str(e)


def test_json_unknown_key_and_bad_value(tmp_path):
    path = tmp_path / "typo.json"
    path.write_text(json.dumps({"preset": "clear", "mie": {"gg": 0.7}}))
    _raises_naming(ValueError, "mie.gg", welkin.Atmosphere.from_json, path)
    path.write_text(json.dumps({"preset": "clear", "mie": {"g": 3.0}}))
    _raises_naming(ValueError, "mie.g", welkin.Atmosphere.from_json, path)


def test_missing_json_file(tmp_path):
    path = tmp_path / "missing.json"
    with pytest.raises((ValueError, OSError)) as info:
        welkin.Atmosphere.from_json(path)
    assert str(path) in str(info.value)


# --- the sun ------------------------------------------------------------------------------


def test_sun_at_zenith_matches_the_vertical_optical_depth(atm):
    """Closed form: straight up, every constituent's column is its profile's integral."""
    sun = welkin.sun(atm, 0.0, (0.0, 0.0, 1.0))
    top = atm.atmosphere_thickness_m
    column_rayleigh = 8000.0 * (1.0 - np.exp(-top / 8000.0))
    column_mie = 1200.0 * (1.0 - np.exp(-top / 1200.0))
    column_ozone = 15e3  # tent 10-25-40 km of height 1
    tau = (
        atm.rayleigh_scattering * column_rayleigh
        + atm.mie_extinction * column_mie
        + atm.absorption_extinction * column_ozone
    )
    np.testing.assert_allclose(sun.transmittance, np.exp(-tau), rtol=1e-6)
    assert sun.visible_fraction == 1.0
    np.testing.assert_allclose(sun.direct_irradiance, atm.solar_irradiance * np.exp(-tau), rtol=1e-5)
    np.testing.assert_array_equal(sun.wavelengths_nm, atm.wavelengths_nm)
    rgb = sun.direct_irradiance_rgb
    assert rgb.shape == (3,) and np.all(rgb > 0.0)
    np.testing.assert_allclose(
        rgb, welkin.spectrum_to_rgb(sun.direct_irradiance, atm.wavelengths_nm, lambda_power=0), rtol=1e-6
    )


def test_sun_below_the_horizon_delivers_nothing(atm):
    e = np.radians(-10.0)
    sun = welkin.sun(atm, 0.0, (np.cos(e), 0.0, np.sin(e)))
    assert sun.visible_fraction == 0.0
    np.testing.assert_array_equal(sun.direct_irradiance, 0.0)


def test_sun_bad_input(atm):
    _raises_naming(ValueError, "altitude_m", welkin.sun, atm, -5.0, (0.0, 0.0, 1.0))
    _raises_naming(ValueError, "sun_direction", welkin.sun, atm, 0.0, (0.0, 0.0, 0.0))
    _raises_naming(ValueError, "sun_direction", welkin.sun, atm, 0.0, (0.0, 1.0))


# --- colour and equirect ------------------------------------------------------------------


def test_spectral_wavelengths():
    w = welkin.spectral_wavelengths_nm()
    assert w.shape == (48,) and w[0] == 360.0 and w[-1] == 830.0
    np.testing.assert_allclose(np.diff(w), 10.0)
    assert len(welkin.spectral_wavelengths_nm(step_nm=5.0)) == 95


def test_spectrum_to_rgb_shapes_and_linearity():
    w = welkin.spectral_wavelengths_nm()
    rng = np.random.default_rng(1)
    spectra = rng.uniform(0.0, 1.0, size=(5, len(w)))
    rgb = welkin.spectrum_to_rgb(spectra, w)
    assert rgb.shape == (5, 3) and rgb.dtype == np.float32
    assert welkin.spectrum_to_rgb(spectra[0], w).shape == (3,)
    np.testing.assert_allclose(welkin.spectrum_to_rgb(spectra[0], w), rgb[0], rtol=1e-6)
    np.testing.assert_allclose(welkin.spectrum_to_rgb(2.0 * spectra, w), 2.0 * rgb, rtol=1e-6)
    three = welkin.spectrum_to_rgb(np.ones((2, 3)), [680.0, 550.0, 440.0])
    assert three.shape == (2, 3)


def test_spectrum_to_rgb_bad_input():
    _raises_naming(ValueError, "spectra", welkin.spectrum_to_rgb, np.ones((2, 4)), [680.0, 550.0, 440.0])
    with pytest.raises(ValueError):
        welkin.spectrum_to_rgb(np.ones(2), [680.0, 550.0])  # fewer than 3 wavelengths


def test_equirect_matches_blenders_mapping():
    # u = -atan2(y, x) / 2pi + 1/2, v = atan2(z, hypot(x, y)) / pi + 1/2 (docs/design.md).
    dirs = np.array(
        [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -2.0],
            [1.0, 1.0, np.sqrt(2.0)],
        ]
    )
    expected = np.array([[0.5, 0.5], [0.25, 0.5], [0.75, 0.5], [0.5, 1.0], [0.5, 0.0], [0.375, 0.75]])
    np.testing.assert_allclose(welkin.direction_to_equirect(dirs), expected, atol=1e-12)
    assert welkin.direction_to_equirect(dirs[1]).shape == (2,)


def test_equirect_round_trip(view_directions):
    uv = welkin.direction_to_equirect(3.0 * view_directions)
    assert uv.shape == (len(view_directions), 2)
    back = welkin.equirect_to_direction(uv)
    np.testing.assert_allclose(back, view_directions, atol=1e-12)
    assert welkin.equirect_to_direction(uv[0]).shape == (3,)


def test_equirect_pixel_directions_are_pixel_centres_top_row_first():
    width, height = 8, 4
    d = welkin.equirect_pixel_directions(width, height)
    assert d.shape == (height, width, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=2), 1.0, atol=1e-12)
    uv = welkin.direction_to_equirect(d.reshape(-1, 3)).reshape(height, width, 2)
    i, j = np.meshgrid(np.arange(width), np.arange(height))
    np.testing.assert_allclose(uv[..., 0], (i + 0.5) / width, atol=1e-12)
    np.testing.assert_allclose(uv[..., 1], 1.0 - (j + 0.5) / height, atol=1e-12)
    _raises_naming(ValueError, "width", welkin.equirect_pixel_directions, 0, 4)


def test_equirect_bad_input():
    _raises_naming(
        ValueError, "view_directions[1]", welkin.direction_to_equirect, [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]
    )
    _raises_naming(ValueError, "view_directions", welkin.direction_to_equirect, [1.0, 2.0])
    _raises_naming(ValueError, "uv[0][1]", welkin.equirect_to_direction, [[0.5, np.nan]])
    _raises_naming(ValueError, "uv", welkin.equirect_to_direction, np.zeros((2, 3)))


# --- the module ---------------------------------------------------------------------------


def test_version_and_docstrings():
    assert re.fullmatch(r"\d+\.\d+\.\d+", welkin.__version__)
    doc = welkin.sky_radiance.__doc__
    for phrase in (
        "W m^-2 sr^-1 nm^-1",
        "Z up",
        "view_directions",
        "sun_direction",
        "altitude_m",
        "KeyboardInterrupt",
    ):
        assert phrase in doc, phrase
    for obj in (
        welkin,
        welkin.Atmosphere,
        welkin.Atmosphere.preset,
        welkin.Atmosphere.from_json,
        welkin.Atmosphere.to_json,
        welkin.sun,
        welkin.SunRadiometry,
        welkin.methods,
        welkin.spectrum_to_rgb,
        welkin.direction_to_equirect,
        welkin.equirect_to_direction,
        welkin.spectral_wavelengths_nm,
        welkin.DensityProfile,
    ):
        assert obj.__doc__ and len(obj.__doc__.strip()) > 20, obj


# --- hostile input (issue 18, items 5 and 6) ------------------------------------------------


def test_json_from_a_device_or_a_directory_is_an_os_error_saying_so(tmp_path):
    _raises_naming(OSError, "character device", welkin.Atmosphere.from_json, "/dev/zero")
    _raises_naming(OSError, "is a directory", welkin.SceneDescription.from_json, str(tmp_path))


def test_json_number_overflow_names_the_key_path_and_the_file(tmp_path):
    path = tmp_path / "atm.json"
    path.write_text('{"preset": "clear", "mie": {"g": 1e999}}')
    e = _raises_naming(ValueError, "mie.g", welkin.Atmosphere.from_json, path)
    assert "number out of range" in str(e) and str(path) in str(e)


def test_a_render_larger_than_memory_is_a_memory_error_not_a_value_error():
    scene = welkin.SceneDescription.from_json_string(
        json.dumps(
            {
                "version": 1,
                "camera": {
                    "matrix_world": [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 2], [0, 0, 0, 1]],
                    "type": "PERSP",
                    "lens_mm": 50,
                },
                "resolution": {"x": 65536, "y": 65536, "percentage": 100},
            }
        )
    )
    depth = np.zeros((1, 1), np.float32)
    with pytest.raises(MemoryError, match="resolution"):
        welkin.aerial_perspective(scene, depth)


def _python_with_numpy_2():
    """A Python 3.11 on this machine other than the one the module was built for, whose
    NumPy is 2.x (the pyenv python3 here), or None."""
    import shutil
    import subprocess
    import sys

    for name in ("python3", "python3.11"):
        path = shutil.which(name)
        if path is None or pathlib.Path(path).resolve() == pathlib.Path(sys.executable).resolve():
            continue
        r = subprocess.run(
            [
                path,
                "-c",
                "import sys, numpy; print(sys.version_info[:2] == (3, 11)"
                " and numpy.__version__.split('.')[0], sys.executable)",
            ],
            capture_output=True,
            text=True,
        )
        if r.returncode == 0 and r.stdout.split()[0] not in ("False", "1"):
            return r.stdout.split()[1]
    return None


def test_a_module_that_cannot_read_numpy_2_arrays_refuses_numpy_2_at_import():
    # Debian's pybind11 2.10 (this build) reads every row of a NumPy 2 array as its first:
    # the module must refuse to load beside NumPy 2 rather than return wrong radiance.
    import subprocess

    python = _python_with_numpy_2()
    if python is None:
        pytest.skip("no Python 3.11 with NumPy 2 on this machine besides the module's own")
    build = pathlib.Path(welkin.__file__).parent
    r = subprocess.run(
        [python, "-c", "import welkin"],
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(build), "PATH": "/usr/bin:/bin"},
    )
    if "pybind11 2.1" in r.stderr and "reads NumPy 1.x arrays only" in r.stderr:
        assert r.returncode != 0
        return
    # A module built with pybind11 >= 2.12 loads, and reads every row.
    assert r.returncode == 0, r.stderr
    probe = (
        "import numpy as np, welkin; a = welkin.Atmosphere.preset('clear'); "
        "d = np.array([[0, 0, 1.0], [1, 0, 0.05]]); "
        "L = welkin.sky_radiance(a, 0.0, np.array([0.5, 0.2, 0.6]), d, output='rgb'); "
        "assert abs(L[0][2] - L[1][2]) > 1e-3 * abs(L[0][2]), L"
    )
    r = subprocess.run(
        [python, "-c", probe],
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(build), "PATH": "/usr/bin:/bin"},
    )
    assert r.returncode == 0, r.stderr
