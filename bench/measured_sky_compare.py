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
With --docs the table goes into docs/validation.md between its "measured-sky" markers.
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
    parser.add_argument("--docs", action="store_true", help="write the table into docs/validation.md")
    args = parser.parse_args()
    text = table()
    print(text)
    if args.docs:
        path = ROOT / "docs" / "validation.md"
        doc = path.read_text()
        begin, end = "<!-- measured-sky:begin -->", "<!-- measured-sky:end -->"
        i, j = doc.index(begin) + len(begin), doc.index(end)
        path.write_text(doc[:i] + "\n" + text + "\n" + doc[j:])


if __name__ == "__main__":
    main()
