# SPDX-License-Identifier: Apache-2.0
"""The `lut` method against `raymarch` with OPAC's layered aerosol profile and with the one
exponential the presets use instead (src/atmosphere/presets.cpp).

    PYTHONPATH=build /usr/bin/python3 bench/lut_layered_profile.py [--docs]

OPAC (Hess, Koepke & Schult 1998) puts each type's aerosol in a mixing layer of height H
with exp(-h / Z) inside and (almost) nothing above: a density that drops to zero at H. The
presets take one exponential with the same surface extinction and the same column (scale
height Z (1 - exp(-H / Z))). This script builds each OPAC preset both ways and measures,
over 400 directions of the upper hemisphere plus the zenith, at 680/550/440 nm, observers
at 0 and 3 km, suns at 5, 30 and 70 degrees: the relative difference |lut / raymarch - 1|
(median, 95th percentile, worst, and at the zenith), and `raymarch`'s own step error
(its default 64/32 steps against 256/128) for scale. --docs prints the table for
docs/validation.md.
"""

import argparse
import math

import numpy as np

import welkin

# preset: (Z, H) of OPAC's profile, m.
PROFILES = {
    "clear_day": (8000.0, 2000.0),
    "hazy": (8000.0, 2000.0),
    "polluted": (8000.0, 2000.0),
    "desert_dust": (2000.0, 6000.0),
    "maritime": (1000.0, 2000.0),
}
SUNS = (5.0, 30.0, 70.0)
ALTITUDES = (0.0, 3000.0)
WAVELENGTHS = [680.0, 550.0, 440.0]


def layered(preset):
    """The preset with OPAC's mixing layer: exp(-h / Z) up to H, 0 above; same surface
    extinction, so the column is the same Z (1 - exp(-H / Z))."""
    z, h = PROFILES[preset]
    atm = welkin.Atmosphere.preset(preset, WAVELENGTHS)
    atm.mie_density = welkin.DensityProfile(
        [
            welkin.DensityLayer(width_m=h, exp_term=1.0, exp_scale_per_m=-1.0 / z),
            welkin.DensityLayer(width_m=0.0, constant=0.0),
        ]
    )
    atm.validate()
    return atm


def directions(n=400):
    i = np.arange(n) + 0.5
    z = 1.0 - i / n
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(1.0 - z * z)
    upper = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    return np.ascontiguousarray(np.concatenate([[[0.0, 0.0, 1.0]], upper]))


def measure(atm):
    """(median, p95, max, zenith) of |lut / raymarch - 1| and raymarch's own p95 step error,
    over every sun, altitude, direction and wavelength."""
    dirs = directions()
    errs, zeniths, steps = [], [], []
    for alt in ALTITUDES:
        for sun in SUNS:
            e = math.radians(sun)
            s = (math.cos(e), 0.0, math.sin(e))
            lut = welkin.sky_radiance(atm, alt, s, dirs, "lut")
            march = welkin.sky_radiance(atm, alt, s, dirs, "raymarch")
            fine = welkin.sky_radiance(atm, alt, s, dirs, "raymarch", steps=256, sun_steps=128)
            err = np.abs(lut / march - 1.0)
            errs.append(err[1:].ravel())
            zeniths.append(err[0])
            steps.append(np.abs(march / fine - 1.0).ravel())
    e = np.concatenate(errs)
    return (
        float(np.median(e)),
        float(np.percentile(e, 95)),
        float(e.max()),
        float(np.max(zeniths)),
        float(np.percentile(np.concatenate(steps), 95)),
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--docs", action="store_true", help="print the table for docs/validation.md")
    args = parser.parse_args()
    rows = []
    for preset in PROFILES:
        for label, atm in (
            ("one exponential (the preset)", welkin.Atmosphere.preset(preset, WAVELENGTHS)),
            ("OPAC's mixing layer", layered(preset)),
        ):
            rows.append((preset, label, *measure(atm)))
            if not args.docs:
                print(rows[-1], flush=True)
    print("| preset | aerosol profile | median | p95 | worst | worst at the zenith | raymarch's own p95 |")
    print("|---|---|---|---|---|---|---|")
    for preset, label, med, p95, worst, zen, own in rows:
        print(
            f"| {preset} | {label} | {med:.2%} | {p95:.2%} | {worst:.2%} | {zen:.2%} | {own:.2%} |".replace(
                "%", " %"
            )
        )


if __name__ == "__main__":
    main()
