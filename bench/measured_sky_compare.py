# SPDX-License-Identifier: Apache-2.0
"""Welkin's clear skies against the CIE standard general sky's clear types: how the
brightness is spread over the sky (the aureole, the horizon, the dark point opposite).

    PYTHONPATH=build /usr/bin/python3 bench/measured_sky_compare.py [--docs]

The CIE standard general sky (ISO 15469:2004 / CIE S 011/E:2003; Kittler, Perez & Darula
1998, "A set of standard skies characterizing daylight conditions for computer and
energy conscious design", Report of Project US-SK 92 052) gives the luminance of a sky
element relative to the zenith's as a product of a gradation and an indicatrix fitted
to measured sky scans (Tokyo, Berkeley, Bratislava, Sydney):
    L(Z, chi) / L_z = f(chi) phi(Z) / (f(Z_s) phi(0)),
    phi(Z) = 1 + a exp(b / cos Z)   (phi = 1 at the horizon),
    f(chi) = 1 + c (exp(d chi) - exp(d pi / 2)) + e cos^2 chi,
Z the element's zenith angle, chi its angle from the sun, Z_s the sun's zenith angle. The
clear types: 11 "white-blue sky with distinct solar corona" (a, b, c, d, e = -1, -0.55,
10, -3, 0.45), 12 "CIE standard clear sky, low illuminance turbidity" (-1, -0.32, 10, -3,
0.45) and 13 "CIE standard clear sky, polluted atmosphere" (-1, -0.32, 16, -3, 0.30).

Welkin: the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of welkin.sky_radiance (lut,
RGB) over the same directions, divided by its zenith's. Per preset and sun elevation the
table gives three ratios of the sky's own brightness (each L / L at the named place):
aureole, 5 degrees from the sun over 50 degrees from it, both on the sun's almucantar;
horizon, the horizon under the sun over the zenith; anti, the horizon opposite the sun over
the zenith; and the median over the upper hemisphere (a 10-degree grid, excluding 5 degrees
around the sun) of |log(L_welkin / L_cie)| for the nearest CIE type, as a percentage.

Colour. Measured clear skylight: Hernandez-Andres, Romero & Lee 2001 ("Colorimetric and
spectroradiometric characteristics of narrow-field-of-view clear skylight in Granada,
Spain", JOSA A 18(2), 412-420: 1500 spectra in 44 directions, correlated colour
temperatures 3800 K to infinity, V-shaped along the solar meridian, lowest at the
horizons and near the sun, highest between) and Chain, Dumortier & Fontoynont 1999 ("A
comprehensive model of luminance, correlated colour temperature and spectral
distribution of skylight: comparison with experimental data", Solar Energy 65(5),
285-295), whose fit to the Lyon sky scans gives a clear (CIE type 12) sky element's CCT
from its luminance L (cd/m^2):  T = 10^6 / (-132.1 + 59.77 log10 L)  K.
The colour table: Welkin's CCT (nearest point of the Planckian locus in CIE 1960 uv, the
locus from Planck's law through the same CIE 1931 functions) at the zenith, on the solar
meridian 90 degrees from the sun, 5 degrees from the sun, and at the horizon under and
opposite the sun, from the default four-wavelength RGB (rec709 -> XYZ); Chain et al.'s CCT
at Welkin's own luminance (683 lm/W times Y) at the first three; the median over the
10-degree grid (elements of at least 1000 cd/m^2, the fit's daylight range) of the
difference Welkin - Chain in mired (10^6 / T, the scale on which equal steps look alike);
Duv over the grid (the distance from the Planckian locus in CIE 1960 uv, positive towards
green: D65's is +0.0032), which says how near the daylight locus the sky's colours lie;
and the largest CIE 1931 xy distance over the grid between the four-wavelength RGB and the
48-wavelength spectral path (the same lut method).
A third table changes clear_day one ingredient at a time (ozone, the ground, the
aerosol's absorption and amount); a fourth gives the light on a horizontal ground, sun and
sky together, against Granada's typical daylight of 5700 K (Hernandez-Andres, Romero,
Nieves & Lee 2001, JOSA A 18(6), 1325-1335).
With --sheet DIR (the tiles `bench/time_of_day_sheet.py --keep DIR` kept) it also measures
the contact sheet's skies, Welkin's add-on world beside Blender's: the CCT 45 degrees up
looking away from the sun, the CCT 5 degrees above the sun, and the luminance there over
the luminance 45 degrees up away from it (the glow against the blue).
With --docs the tables go into docs/validation.md between their "measured-sky" and
"measured-colour" markers.
"""

import argparse
import math
import pathlib

import numpy as np

import welkin

ROOT = pathlib.Path(__file__).resolve().parents[1]
CIE_TYPES = {
    11: (-1.0, -0.55, 10.0, -3.0, 0.45),
    12: (-1.0, -0.32, 10.0, -3.0, 0.45),
    13: (-1.0, -0.32, 16.0, -3.0, 0.30),
}
PRESETS = ("clear", "clear_day", "hazy", "bruneton2017")
ELEVATIONS = (60.0, 40.0, 20.0, 10.0, 5.0)
LUMA = np.array([0.2126, 0.7152, 0.0722])


def cie_relative(kind, zenith, chi, sun_zenith):
    a, b, c, d, e = CIE_TYPES[kind]
    cosz = np.cos(zenith)
    phi = np.where(cosz > 1e-9, 1.0 + a * np.exp(b / np.maximum(cosz, 1e-9)), 1.0)
    f = 1.0 + c * (np.exp(d * chi) - math.exp(d * math.pi / 2)) + e * np.cos(chi) ** 2
    fs = 1.0 + c * (math.exp(d * sun_zenith) - math.exp(d * math.pi / 2)) + e * math.cos(sun_zenith) ** 2
    return f * phi / (fs * (1.0 + a * math.exp(b)))


def direction(elevation, azimuth):
    return np.stack(
        [np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)], axis=-1
    )


def probes(sun_el):
    """Named directions (sun at azimuth 0) and a 10-degree grid over the upper hemisphere."""
    s = math.radians(sun_el)

    def almucantar(chi_deg):  # the azimuth at the sun's elevation chi_deg from the sun
        c = (math.cos(math.radians(chi_deg)) - math.sin(s) ** 2) / math.cos(s) ** 2
        return math.acos(max(-1.0, min(1.0, c)))

    named = {
        "zenith": (math.pi / 2, 0.0),
        "near": (s, almucantar(5.0)),
        "far": (s, almucantar(50.0)),
        "horizon": (math.radians(0.5), 0.0),
        "anti": (math.radians(0.5), math.pi),
    }
    el, az = np.meshgrid(np.radians(np.arange(5.0, 90.0, 10.0)), np.radians(np.arange(0.0, 360.0, 10.0)))
    grid = np.stack([el.ravel(), az.ravel()], axis=1)
    return named, grid


def angle_from_sun(el, az, sun_el):
    s = direction(math.radians(sun_el), 0.0)
    return np.arccos(np.clip(direction(el, az) @ s, -1.0, 1.0))


def ratios(lum):
    return lum["near"] / lum["far"], lum["horizon"] / lum["zenith"], lum["anti"] / lum["zenith"]


def row(preset, sun_el):
    atm = welkin.Atmosphere.preset(preset)
    named, grid = probes(sun_el)
    pts = np.array(list(named.values()) + [tuple(g) for g in grid])
    sun_vec = direction(math.radians(sun_el), 0.0)
    dirs = direction(pts[:, 0], pts[:, 1])
    rgb = welkin.sky_radiance(atm, 0.0, tuple(sun_vec), np.ascontiguousarray(dirs), "lut", "rgb")
    y = rgb @ LUMA
    lum = dict(zip(named, y[: len(named)]))
    chi = angle_from_sun(pts[:, 0], pts[:, 1], sun_el)
    zen = math.pi / 2 - pts[:, 0]
    best = None
    for kind in CIE_TYPES:
        cie = cie_relative(kind, zen, chi, math.pi / 2 - math.radians(sun_el))
        cie_named = dict(zip(named, cie[: len(named)]))
        mask = chi[len(named) :] > math.radians(5.0)
        dev = np.median(np.abs(np.log((y[len(named) :] / lum["zenith"]) / cie[len(named) :]))[mask])
        if best is None or dev < best[1]:
            best = (kind, dev, ratios(cie_named))
    return ratios(lum), best


COLOUR_PRESETS = ("clear_day", "clear", "hazy", "polluted", "desert_dust", "maritime", "bruneton2017")
COLOUR_ELEVATIONS = (60.0, 40.0, 20.0, 10.0)
LUMINOUS_EFFICACY = 683.0  # lm/W: welkin's RGB carries no 683 factor (spectrum_to_rgb)
_LOCUS = {}


def to_xyz(rgb, space="rec709"):
    """Linear RGB of `space` (W m^-2 sr^-1) -> CIE XYZ, the inverse of welkin's own matrix."""
    return np.asarray(rgb, float) @ np.linalg.inv(welkin.color_space_matrix("xyz", space)).T


def uv1960(xyz):
    x, y, z = np.atleast_2d(xyz).T
    den = x + 15.0 * y + 3.0 * z
    return np.stack([4.0 * x / den, 6.0 * y / den], axis=1)


def planckian_locus():
    """CIE 1960 uv of black bodies 1600 K .. 10^6 K, through welkin's CIE 1931 functions."""
    if not _LOCUS:
        wl = np.asarray(welkin.spectral_wavelengths_nm())
        temps = 1.0e6 / np.linspace(1.0e6 / 1600.0, 1.0, 6000)  # even in mired
        lam = wl[None, :] * 1e-9
        spectra = 1.0 / (lam**5 * np.expm1(1.4388e-2 / (lam * temps[:, None])))
        spectra /= spectra.max(axis=1, keepdims=True)
        # Rec.2020 holds every black body from 1600 K up, so its gamut mapping leaves them be.
        rgb = np.asarray(welkin.spectrum_to_rgb(spectra, wl, 0.0, color_space="rec2020"))
        _LOCUS["T"], _LOCUS["uv"] = temps, uv1960(to_xyz(rgb, "rec2020"))
    return _LOCUS["T"], _LOCUS["uv"]


def cct(xyz):
    """Correlated colour temperature (K): the nearest locus point in CIE 1960 uv."""
    temps, locus = planckian_locus()
    uv = uv1960(xyz)
    return temps[np.argmin(((uv[:, None, :] - locus[None]) ** 2).sum(axis=2), axis=1)]


def duv(xyz):
    """Distance from the Planckian locus in CIE 1960 uv, positive above it (towards green)."""
    _temps, locus = planckian_locus()
    uv = uv1960(xyz)
    nearest = locus[np.argmin(((uv[:, None, :] - locus[None]) ** 2).sum(axis=2), axis=1)]
    return np.linalg.norm(uv - nearest, axis=1) * np.sign(uv[:, 1] - nearest[:, 1])


def duv_over_the_sky(preset, sun_el):
    """Duv's median and range over the 10-degree grid of the upper hemisphere."""
    _named, grid = probes(sun_el)
    dirs = np.ascontiguousarray(direction(grid[:, 0], grid[:, 1]))
    sun_vec = tuple(direction(math.radians(sun_el), 0.0))
    d = duv(to_xyz(welkin.sky_radiance(welkin.Atmosphere.preset(preset), 0.0, sun_vec, dirs, "lut", "rgb")))
    return np.median(d), d.min(), d.max()


def chain_cct(luminance):
    """Chain, Dumortier & Fontoynont 1999: a clear sky element's CCT from its luminance."""
    den = -132.1 + 59.77 * np.log10(np.maximum(luminance, 1e-9))
    return np.where(den > 0.0, 1.0e6 / np.maximum(den, 1e-9), np.inf)


def scaled_aerosol(factor):
    def apply(atm):
        atm.mie_extinction = [factor * v for v in atm.mie_extinction]
        atm.mie_scattering = [factor * v for v in atm.mie_scattering]

    return apply


# What each ingredient of clear_day does to its colour and its sunset glow: one change at a
# time (a sensitivity, not a preset).
FACTORS = (
    ("clear_day", lambda atm: None),
    ("no ozone", lambda atm: setattr(atm, "absorption_extinction", [0.0] * atm.channels)),
    ("ground: black", lambda atm: setattr(atm, "ground_albedo", [0.0] * atm.channels)),
    ("ground: grey 0.3", lambda atm: setattr(atm, "ground_albedo", [0.3] * atm.channels)),
    ("aerosol: no absorption (ω = 1)", lambda atm: setattr(atm, "mie_scattering", list(atm.mie_extinction))),
    ("aerosol: τ₅₅₀ 0.06 (half)", scaled_aerosol(0.5)),
    ("aerosol: τ₅₅₀ 0.018 (Blender 5's default)", scaled_aerosol(0.018 / 0.12)),
)


def colour_row(preset, sun_el, change=None):
    named, grid = probes(sun_el)
    named["side"] = (math.radians(90.0 - sun_el), math.pi)  # solar meridian, 90 deg from the sun
    keys = ("zenith", "side", "near", "horizon", "anti")
    pts = np.array([named[k] for k in keys] + [tuple(g) for g in grid])
    sun_vec = direction(math.radians(sun_el), 0.0)
    dirs = np.ascontiguousarray(direction(pts[:, 0], pts[:, 1]))
    atm = welkin.Atmosphere.preset(preset)
    if change is not None:
        change(atm)
    xyz = to_xyz(welkin.sky_radiance(atm, 0.0, tuple(sun_vec), dirs, "lut", "rgb"))
    if change is not None:  # the spectral path is for the presets themselves
        return (
            cct(xyz)[:3],
            None,
            LUMINOUS_EFFICACY * xyz[:, 1],
            *chain_median(xyz, pts, sun_el, len(keys)),
            None,
        )
    wl = welkin.spectral_wavelengths_nm()
    spectral = welkin.sky_radiance(welkin.Atmosphere.preset(preset, wl), 0.0, tuple(sun_vec), dirs, "lut")
    xyz_s = to_xyz(welkin.spectrum_to_rgb(spectral, wl, color_space="rec2020"), "rec2020")

    def xy(v):
        return v[:, :2] / v.sum(axis=1, keepdims=True)

    temps = cct(xyz)
    lum = LUMINOUS_EFFICACY * xyz[:, 1]
    chain = chain_cct(lum)
    (mired,) = chain_median(xyz, pts, sun_el, len(keys))
    dxy = float(np.max(np.linalg.norm(xy(xyz) - xy(xyz_s), axis=1)))
    return dict(zip(keys, temps)), dict(zip(keys, chain)), dict(zip(keys, lum)), mired, dxy


def chain_median(xyz, pts, sun_el, n):
    """The median over the grid (after the n named places) of Welkin - Chain, in mired."""
    temps, lum = cct(xyz[n:]), LUMINOUS_EFFICACY * xyz[n:, 1]
    chi = angle_from_sun(pts[n:, 0], pts[n:, 1], sun_el)
    use = (lum >= 1000.0) & (chi > math.radians(5.0))
    return (
        float(np.median(1.0e6 / temps[use] - 1.0e6 / chain_cct(lum[use]))) if use.any() else float("nan"),
    )


def glow(change, sun_el=1.0):
    """Luminance 5 degrees from a low sun (on its almucantar) over the zenith's."""
    named, _grid = probes(sun_el)
    dirs = np.ascontiguousarray(direction(*np.array([named["near"], named["zenith"]]).T))
    atm = welkin.Atmosphere.preset("clear_day")
    change(atm)
    y = to_xyz(
        welkin.sky_radiance(atm, 0.0, tuple(direction(math.radians(sun_el), 0.0)), dirs, "lut", "rgb")
    )[:, 1]
    return y[0] / y[1]


def factor_table():
    lines = [
        "| change to clear_day | sun 60°: CCT zenith / 90° / 5° from the sun (K) | Welkin − Chain (mired) "
        "| sun 20°: CCT zenith / 90° / 5° (K) | Welkin − Chain (mired) | sun 1°: luminance 5° from the sun "
        "over the zenith's |",
        "|---|---|---|---|---|---|",
    ]
    for name, change in FACTORS:
        cells = []
        for sun_el in (60.0, 20.0):
            temps, _c, _lum, mired, _dxy = colour_row("clear_day", sun_el, change)
            cells.append(f"{' / '.join(kelvin(t) for t in temps)} | {mired:+.0f}")
        lines.append(f"| {name} | {' | '.join(cells)} | {glow(change):.1f} |")
    return "\n".join(lines)


def daylight_table(preset="clear_day", n=64):
    """The light on a horizontal ground: the sky's irradiance (a midpoint rule in the cosine
    of the zenith angle and the azimuth) plus the sun's direct beam (welkin.sun)."""
    mu, az = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(2 * n) + 0.5) / (2 * n) * 2.0 * math.pi)
    dirs = np.ascontiguousarray(direction(np.arcsin(mu.ravel()), az.ravel()))
    weight = mu.ravel() * (2.0 * math.pi / (2 * n * n))  # cos(zenith) dOmega
    atm = welkin.Atmosphere.preset(preset)
    lines = [
        f"| sun | {preset}: global CCT (K) | illuminance (lux) | the sky's part: CCT (K) | its illuminance (lux) |",
        "|---|---|---|---|---|",
    ]
    for sun_el in (60.0, 40.0, 20.0, 10.0):
        sun_vec = tuple(direction(math.radians(sun_el), 0.0))
        sky = weight @ np.asarray(welkin.sky_radiance(atm, 0.0, sun_vec, dirs, "lut", "rgb"))
        beam = np.asarray(welkin.sun(atm, 0.0, sun_vec).direct_irradiance_rgb) * math.sin(
            math.radians(sun_el)
        )
        xyz = to_xyz(np.array([sky + beam, sky]))
        t, lux = cct(xyz), LUMINOUS_EFFICACY * xyz[:, 1]
        lines.append(f"| {sun_el:g}° | {kelvin(t[0])} | {lux[0]:.0f} | {kelvin(t[1])} | {lux[1]:.0f} |")
    return "\n".join(lines)


def kelvin(t):
    return "∞" if not np.isfinite(t) or t > 50000.0 else f"{100 * round(t / 100):.0f}"


def colour_table():
    lines = [
        "| preset | sun | Welkin CCT (K): zenith / 90° from the sun / 5° from it / horizon under / "
        "opposite | Chain et al. at Welkin's luminance: zenith / 90° / 5° | median Welkin − Chain "
        "(mired) | Duv over the sky: median (range) | RGB vs spectral, worst Δxy |",
        "|---|---|---|---|---|---|---|",
    ]
    for preset in COLOUR_PRESETS:
        for sun_el in COLOUR_ELEVATIONS:
            t, c, _lum, mired, dxy = colour_row(preset, sun_el)
            d = duv_over_the_sky(preset, sun_el)
            lines.append(
                f"| {preset} | {sun_el:g}° | "
                + " / ".join(kelvin(t[k]) for k in ("zenith", "side", "near", "horizon", "anti"))
                + " | "
                + " / ".join(kelvin(c[k]) for k in ("zenith", "side", "near"))
                + f" | {mired:+.0f} | {d[0]:+.4f} ({d[1]:+.4f} .. {d[2]:+.4f}) | {dxy:.4f} |"
            )
    return "\n".join(lines)


def write_docs(text, name):
    path = ROOT / "docs" / "validation.md"
    doc = path.read_text()
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    i, j = doc.index(begin) + len(begin), doc.index(end)
    path.write_text(doc[:i] + "\n" + text + "\n" + doc[j:])


SHEET_SKIES = (
    ("welkin", "Welkin (add-on world)"),
    ("nishita", "Blender Nishita"),
    ("multiple", "Blender Multiple Scattering"),
)
SHEET_ELEVATIONS = (60.0, 20.0, 5.0, 1.0)
# bench/time_of_day_sheet.py's tiles: 120 degrees of azimuth centred on the view, elevation
# -10 to +70 degrees, equirectangular.
SHEET_LAT = (-10.0, 70.0)


def read_tile(path):
    """A kept tile as linear RGB (read_exr gives the channels in the file's sorted order)."""
    pixels, names = welkin.read_exr(str(path))
    return pixels[:, :, [names.index(c) for c in "RGB"]]


def sheet_pixel(tile, elevation_deg):
    """The mean linear RGB of the 3 x 3 pixels at the tile's centre column and elevation."""
    h, w = tile.shape[:2]
    row = int((SHEET_LAT[1] - elevation_deg) / (SHEET_LAT[1] - SHEET_LAT[0]) * h)
    return tile[row - 1 : row + 2, w // 2 - 1 : w // 2 + 2].reshape(-1, 3).mean(axis=0)


def sheet_table(folder):
    folder = pathlib.Path(folder)
    lines = [
        "| sky | sun | CCT 45° up, away from the sun | CCT 5° above the sun | luminance there / 45° up away |",
        "|---|---|---|---|---|",
    ]
    for key, title in SHEET_SKIES:
        for sun_el in SHEET_ELEVATIONS:
            away, toward = (folder / f"{key}_{sun_el:+05.1f}_{v}.exr" for v in ("away", "toward"))
            if not (away.exists() and toward.exists()):
                continue
            blue = sheet_pixel(read_tile(away), 45.0)
            glow = sheet_pixel(read_tile(toward), sun_el + 5.0)
            xyz = to_xyz(np.array([blue, glow]))
            t = cct(xyz)
            lines.append(
                f"| {title} | {sun_el:g}° | {kelvin(t[0])} | {kelvin(t[1])} | {xyz[1, 1] / xyz[0, 1]:.1f} |"
            )
    return "\n".join(lines)


def table():
    lines = [
        "| preset | sun | Welkin aureole / horizon / anti | nearest CIE type | its aureole / horizon / anti | "
        "median deviation |",
        "|---|---|---|---|---|---|",
    ]
    for preset in PRESETS:
        for sun_el in ELEVATIONS:
            w, (kind, dev, c) = row(preset, sun_el)
            lines.append(
                f"| {preset} | {sun_el:g}° | {w[0]:.1f} / {w[1]:.2f} / {w[2]:.2f} | {kind} | "
                f"{c[0]:.1f} / {c[1]:.2f} / {c[2]:.2f} | {100 * (math.exp(dev) - 1):.0f} % |"
            )
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--docs", action="store_true", help="write the tables into docs/validation.md")
    parser.add_argument(
        "--sheet", default=None, help="also measure the contact sheet's kept tiles in this folder"
    )
    args = parser.parse_args()
    text = table()
    print(text)
    colour = colour_table()
    print(colour)
    factors = factor_table()
    print(factors)
    daylight = daylight_table()
    print(daylight)
    if args.docs:
        write_docs(text, "measured-sky")
        write_docs(colour, "measured-colour")
        write_docs(factors, "colour-factors")
        write_docs(daylight, "measured-daylight")
    if args.sheet:
        sheet = sheet_table(args.sheet)
        print(sheet)
        if args.docs:
            write_docs(sheet, "sheet-colour")


if __name__ == "__main__":
    main()
