# SPDX-License-Identifier: Apache-2.0
"""Stability sweep: no sky method ever returns NaN, Inf or negative radiance.

docs/design.md names the places where sky methods are known to break: the camera above the
atmosphere (the sky-view LUT is parametrised for an observer inside it), the sun far
below the horizon (deep twilight, Earth shadow), grazing rays near the horizon at
planet scale (r^2 - R^2 cancels in float32), a Mie phase peak near g = 1, and
atmospheres far from Earth's (none at all, 100 times denser, a very thin or very thick
shell). This sweep runs every method (and `auto`, once it is registered) over those
cases and fails on any value that is not finite, or any radiance below zero, naming the case.

It checks stability only; accuracy is measured by the chart (bench/chart.py) against the
reference method. The reference runs with few paths: noise does not matter here, only
that every estimate is a finite non-negative number.
"""

import math

import numpy as np
import pytest

import welkin


def fibonacci_sphere(n):
    """n unit vectors spread evenly over the sphere (the golden-angle spiral)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def sun_direction(elevation_deg, azimuth_deg=90.0):
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))


def probe_directions(atm, altitude_m, sun_dir):
    """The sphere, plus the rays where methods break: grazing the horizon (the flat one
    and the geometric one of this altitude, a hair above and below each), straight up and
    down, towards the sun and away from it."""
    dirs = [fibonacci_sphere(48)]
    r = atm.bottom_radius_m + altitude_m
    # Geometric horizon: the ray tangent to the ground, elevation -acos(R / r).
    horizon = -math.acos(min(1.0, atm.bottom_radius_m / r))
    elevations = []
    for e0 in (0.0, horizon):
        for de in (0.0, 1e-7, -1e-7, 1e-4, -1e-4, 1e-2, -1e-2):
            elevations.append(e0 + de)
    for e in elevations:
        for az in (0.0, math.pi / 2, math.pi):
            dirs.append([[math.cos(e) * math.cos(az), math.cos(e) * math.sin(az), math.sin(e)]])
    s = np.asarray(sun_dir, dtype=np.float64)
    s = s / np.linalg.norm(s)
    dirs.append(np.array([[0, 0, 1.0], [0, 0, -1.0], s, -s]))
    return np.ascontiguousarray(np.concatenate(dirs, axis=0))


# --- the atmospheres -------------------------------------------------------------------


def _earth():
    return welkin.Atmosphere.preset("bruneton2017")


def _g999(phase):
    def make():
        a = _earth()
        a.mie_phase = phase
        a.mie_g = 0.999
        return a

    return make


def _zero_density():
    a = _earth()
    a.rayleigh_density = welkin.DensityProfile.zero()
    a.mie_density = welkin.DensityProfile.zero()
    a.absorption_density = welkin.DensityProfile.zero()
    return a


def _dense(factor):
    def make():
        a = _earth()
        a.rayleigh_scattering = np.asarray(a.rayleigh_scattering) * factor
        a.mie_scattering = np.asarray(a.mie_scattering) * factor
        a.mie_extinction = np.asarray(a.mie_extinction) * factor
        a.absorption_extinction = np.asarray(a.absorption_extinction) * factor
        return a

    return make


def _thin():
    """A 1 km shell (the density profiles are cut by the top)."""
    a = _earth()
    a.top_radius_m = a.bottom_radius_m + 1e3
    return a


def _thick():
    """A shell half the planet's radius deep with 300 km scale heights."""
    a = _earth()
    a.top_radius_m = 1.5 * a.bottom_radius_m
    a.rayleigh_density = welkin.DensityProfile.exponential(3e5)
    a.mie_density = welkin.DensityProfile.exponential(5e4)
    return a


def _tiny_planet():
    """A 1 km planet with a 400 m shell: every ray is strongly curved."""
    a = _earth()
    a.bottom_radius_m = 1e3
    a.top_radius_m = 1.4e3
    return a


ATMOSPHERES = {
    "earth": _earth,
    "mie_g_0.999_cornette_shanks": _g999("cornette_shanks"),
    "mie_g_0.999_henyey_greenstein": _g999("henyey_greenstein"),
    "zero_density": _zero_density,
    "density_x100": _dense(100.0),
    "thin_1km": _thin,
    "thick_half_radius": _thick,
    "tiny_planet": _tiny_planet,
    "mars": lambda: welkin.Atmosphere.preset("mars"),
    "spectral_20nm": lambda: welkin.Atmosphere.preset("bruneton2017", welkin.spectral_wavelengths_nm(20.0)),
}
# Many wavelengths cost many times more: a smaller grid for them.
SPECTRAL_GRID = ([0.0, 4e5], [-8.0, 0.0, 30.0])

# Earth gets the full (altitude, sun elevation) grid; the odd atmospheres a smaller one.
FULL_ALTITUDES_M = [0.0, 0.5, 1e3, 1e4, 5e4, 6e4 - 1.0, 6e4, 1e5, 4e5, 1e7]
FULL_SUN_ELEVATIONS_DEG = [-90.0, -18.0, -12.0, -8.0, -4.0, -0.5, 0.0, 0.3, 5.0, 45.0, 90.0]
SMALL_ALTITUDES_M = [0.0, 0.5, 1e4, 4e5]
SMALL_SUN_ELEVATIONS_DEG = [-18.0, -8.0, -0.5, 0.0, 10.0, 90.0]

# Each method with a cheap and a default-ish setting; lut also with tiny textures.
METHOD_SETTINGS = {
    "analytic": [{}],
    "lut": [
        {},
        dict(
            transmittance_width=8,
            transmittance_height=4,
            multiscattering_size=4,
            skyview_width=8,
            skyview_height=6,
        ),
    ],
    "raymarch": [dict(steps=64, sun_steps=32), dict(steps=1, sun_steps=1)],
    "reference": [dict(paths=8, seed=5)],
}
if "auto" in welkin.methods():
    METHOD_SETTINGS["auto"] = [{}]


def sweep(method, make_atmosphere, altitudes, sun_elevations):
    atm = make_atmosphere()
    failures = []
    for settings in METHOD_SETTINGS[method]:
        for alt in altitudes:
            for sun_el in sun_elevations:
                s = sun_direction(sun_el)
                dirs = probe_directions(atm, alt, s)
                spectral = welkin.sky_radiance(atm, alt, s, dirs, method=method, **settings)
                # The conversion output="rgb" makes (the same core function).
                rgb = welkin.spectrum_to_rgb(spectral, atm.wavelengths_nm, -3.0)
                for output, L in (("spectral", spectral), ("rgb", rgb)):
                    bad_nonfinite = ~np.isfinite(L)
                    # Radiance is never negative; a Rec.709 colour may be, outside its
                    # gamut (a deep red twilight sky has a negative blue component).
                    bad_negative = np.isfinite(L) & (L < 0.0) & (output == "spectral")
                    if bad_nonfinite.any() or bad_negative.any():
                        rows = np.nonzero((bad_nonfinite | bad_negative).any(axis=1))[0]
                        failures.append(
                            f"{method} {settings} altitude {alt} m, sun {sun_el} deg, "
                            f"{output}: {int(bad_nonfinite.sum())} non-finite, "
                            f"{int(bad_negative.sum())} negative values, e.g. direction "
                            f"{dirs[rows[0]].tolist()} -> {L[rows[0]].tolist()}"
                        )
    return failures


@pytest.mark.parametrize("method", sorted(METHOD_SETTINGS))
def test_earth_full_grid_is_finite_and_non_negative(method):
    # auto runs one of the methods swept here: the small grid checks its choosing.
    grid = (
        (SMALL_ALTITUDES_M, SMALL_SUN_ELEVATIONS_DEG)
        if method == "auto"
        else (FULL_ALTITUDES_M, FULL_SUN_ELEVATIONS_DEG)
    )
    failures = sweep(method, _earth, *grid)
    assert not failures, "\n".join(failures[:20])


@pytest.mark.parametrize("atmosphere", [k for k in ATMOSPHERES if k != "earth"])
@pytest.mark.parametrize("method", sorted(METHOD_SETTINGS))
def test_odd_atmospheres_are_finite_and_non_negative(method, atmosphere):
    grid = (
        SPECTRAL_GRID if atmosphere.startswith("spectral") else (SMALL_ALTITUDES_M, SMALL_SUN_ELEVATIONS_DEG)
    )
    failures = sweep(method, ATMOSPHERES[atmosphere], *grid)
    assert not failures, "\n".join(failures[:20])


def test_zero_density_gives_black_sky():
    """With nothing in the air nothing scatters: every method returns exactly zero (a
    closed form, and the case where 0/0 would appear in a careless normalisation)."""
    atm = _zero_density()
    s = sun_direction(30.0)
    dirs = probe_directions(atm, 0.0, s)
    for method, settings_list in METHOD_SETTINGS.items():
        for settings in settings_list:
            L = welkin.sky_radiance(atm, 0.0, s, dirs, method=method, **settings)
            assert np.all(L == 0.0), f"{method} {settings}: max {float(np.max(L))}"
