#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Fits and validates the default wavelengths' RGB conversion (src/color/color.cpp).

    build/welkin_bench_colour_fit --out DIR
    python3 scripts/fit_colour.py DIR [--search]

Reads the 48-wavelength lut skies written by bench/bench_colour_fit.cpp and prints, in
Markdown: the settings compared (wavelengths and conversion against the 48-wavelength
path: CIE 1931 xy error median / worst, relative luminance error median / 99th
percentile), the errors of the default per preset and altitude, and the fitted Rec.709
matrices (rows R, G, B; columns the wavelengths ascending) that color.cpp carries.
--search also ranks every set of four wavelengths in 400..700 nm, 20 nm apart, by the
fit's worst xy error (minutes).
"""

import itertools
import sys

import numpy as np

# XYZ <-> linear Rec.709 (IEC 61966-2-1), as color.cpp.
RGB_TO_XYZ = np.array(
    [[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]]
)
WL = np.arange(360.0, 831.0, 10.0)
DEFAULT = (440, 480, 560, 620)


def load(folder):
    cases = np.loadtxt(f"{folder}/cases.txt", ndmin=2)
    n = len(cases)
    sky = np.fromfile(f"{folder}/spectra.f32", np.float32).reshape(n, -1, 48).astype(np.float64)
    sun = np.fromfile(f"{folder}/sun.f32", np.float32).reshape(n, 48).astype(np.float64)
    to_xyz = RGB_TO_XYZ @ np.loadtxt(f"{folder}/cie48.txt").reshape(3, 48)
    presets = open(f"{folder}/presets.txt").read().split()
    return cases, sky, sun, to_xyz, presets


def chromaticity(xyz):
    return xyz[:, :2] / xyz.sum(1)[:, None]


def fit(samples, xyz):
    """Least squares of XYZ / Y against samples / Y: relative error per spectrum."""
    a = samples / xyz[:, 1:2]
    return np.stack([np.linalg.lstsq(a, xyz[:, k] / xyz[:, 1], rcond=None)[0] for k in range(3)])


def errors(xyz_fit, xyz):
    return (
        np.linalg.norm(chromaticity(xyz_fit) - chromaticity(xyz), axis=1),
        np.abs(xyz_fit[:, 1] / xyz[:, 1] - 1.0),
    )


def main():
    folder = sys.argv[1]
    cases, sky, sun, to_xyz, presets = load(folder)
    per_case = sky.shape[1]
    spectra = sky.reshape(-1, 48)
    xyz = spectra @ to_xyz.T
    ok = xyz[:, 1] > 0
    spectra, xyz = spectra[ok], xyz[ok]
    case = np.repeat(np.arange(len(cases)), per_case)[ok]
    index = {w: int(np.argmin(np.abs(WL - w))) for w in range(360, 831, 10)}

    def columns(ws):
        return spectra[:, [index[w] for w in ws]]

    if "--search" in sys.argv:
        sub = np.arange(len(xyz)) % 7 == 0
        ranked = []
        for ws in itertools.combinations(range(400, 701, 20), 4):
            m = fit(columns(ws)[sub], xyz[sub])
            e, _ = errors(columns(ws) @ m.T, xyz)
            ranked.append((e.max(), np.median(e), ws))
        ranked.sort()
        print("| wavelengths (nm) | xy worst | xy median |\n|---|---|---|")
        for worst, med, ws in ranked[:8]:
            print(f"| {'/'.join(map(str, ws))} | {worst:.4f} | {med:.4f} |")
        print()

    # Settings: wavelength sets with the tent-function CIE integral (linear interpolation
    # of the samples, as color.cpp does for other sets) and with a fitted matrix. The
    # fitted ones are judged on the half of the spectra they were not fitted to.
    def tent_matrix(ws):
        w = np.array(ws, float)
        fine = np.arange(360.0, 830.0001, 0.25)
        interp = np.stack([np.interp(fine, w, np.eye(len(w))[i]) for i in range(len(w))])
        cmf = np.stack([np.interp(fine, WL, to_xyz[k]) for k in range(3)]) / 10.0
        return cmf @ interp.T * 0.25

    half = np.arange(len(xyz)) % 2 == 0
    print("| setting | channels (SIMD batches) | xy median | xy worst | luminance median | luminance p99 |")
    print("|---|---|---|---|---|---|")
    bruneton = RGB_TO_XYZ @ np.loadtxt(f"{folder}/bruneton3.txt").reshape(3, 3)
    e, ly = errors(columns((680, 550, 440)) @ bruneton.T, xyz)
    print(
        f"| 3 wavelengths 680/550/440, Bruneton 2017's conversion (the former default) | 3 (1) | "
        f"{np.median(e):.4f} | {e.max():.4f} | {np.median(ly):.4f} | {np.percentile(ly, 99):.4f} |"
    )
    rows = [
        ("3 wavelengths 680/550/440, linear interpolation", (440, 550, 680), None),
        ("3 wavelengths 680/550/440, fitted", (440, 550, 680), "fit"),
        ("4 wavelengths 440/480/560/620, linear interpolation", DEFAULT, None),
        ("4 wavelengths 440/480/560/620, fitted (default)", DEFAULT, "fit"),
        ("6 wavelengths 420..670, linear interpolation", (420, 470, 520, 570, 620, 670), None),
        ("8 wavelengths 400..680, linear interpolation", tuple(range(400, 681, 40)), None),
        ("8 wavelengths 400..680, fitted", tuple(range(400, 681, 40)), "fit"),
    ]
    for label, ws, kind in rows:
        if kind == "fit":
            m = fit(columns(ws)[half], xyz[half])
            e, ly = errors(columns(ws)[~half] @ m.T, xyz[~half])
        else:
            e, ly = errors(columns(ws) @ tent_matrix(ws).T, xyz)
        print(
            f"| {label} | {len(ws)} ({-(-len(ws) // 4)}) | {np.median(e):.4f} | {e.max():.4f} | "
            f"{np.median(ly):.4f} | {np.percentile(ly, 99):.4f} |"
        )
    print()

    m_sky = fit(columns(DEFAULT), xyz)
    e, ly = errors(columns(DEFAULT) @ m_sky.T, xyz)
    print("| preset | altitude | xy median | xy worst | luminance median | luminance worst |")
    print("|---|---|---|---|---|---|")
    for p, name in enumerate(presets):
        for alt in (0.0, 1000.0, 3000.0, 10000.0):
            s = (cases[case, 0] == p) & (cases[case, 2] == alt)
            print(
                f"| {name} | {alt / 1000:g} km | {np.median(e[s]):.4f} | {e[s].max():.4f} | "
                f"{np.median(ly[s]):.4f} | {ly[s].max():.4f} |"
            )
    print()

    xyz_sun = sun @ to_xyz.T
    lit = xyz_sun[:, 1] > 1e-6 * xyz_sun[:, 1].max()
    sun_cols = sun[lit][:, [index[w] for w in DEFAULT]]
    m_sun = fit(sun_cols, xyz_sun[lit])
    es, ls = errors(sun_cols @ m_sun.T, xyz_sun[lit])
    print(
        f"Direct sunlight ({lit.sum()} spectra): xy median {np.median(es):.4f}, worst {es.max():.4f}; "
        f"luminance median {np.median(ls):.4f}, worst {ls.max():.4f}.\n"
    )
    xyz_to_rgb = np.linalg.inv(RGB_TO_XYZ)
    np.set_printoptions(precision=10, suppress=True)
    print("kFittedSkyToRgb (columns 440, 480, 560, 620 nm):\n", xyz_to_rgb @ m_sky)
    print("kFittedSunToRgb:\n", xyz_to_rgb @ m_sun)


if __name__ == "__main__":
    main()
