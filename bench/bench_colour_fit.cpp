// SPDX-License-Identifier: Apache-2.0
// Data for the default wavelengths' colour conversion (color.cpp) and its validation:
// 48-wavelength lut skies and direct sunlight over every preset, sun elevations -10..90
// degrees, observers at 0, 1, 3 and 10 km, 160 directions over the upper hemisphere (a
// Fibonacci spiral, uniform in solid angle). scripts/fit_colour.py reads them, fits the
// matrices and reports the errors (docs/validation.md, "Colour").
//
//   build/welkin_bench_colour_fit --out DIR
//
// Writes DIR/spectra.f32 (cases x 160 x 48 float32, W m^-2 sr^-1 nm^-1), DIR/sun.f32
// (cases x 48, W m^-2 nm^-1), DIR/cases.txt (preset index, sun elevation deg, altitude m),
// DIR/presets.txt, DIR/cie48.txt (the 3 x 48 Rec.709 matrix of the spectral path) and
// DIR/bruneton3.txt (the 3 x 3 one of Bruneton 2017's conversion at 680/550/440 nm).
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/sun.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"
#include "welkin/sky/lut.hpp"

using namespace welkin;

int main(int argc, char** argv) {
    CLI::App app{"Welkin colour-fit data"};
    std::string dir = ".";
    app.add_option("--out", dir, "output folder (must exist)");
    CLI11_PARSE(app, argc, argv);

    const std::vector<double> wl = spectral_wavelengths_nm(10.0);
    const int n = 160;
    std::vector<glm::dvec3> d;
    for (int k = 0; k < n; ++k) {
        const double z = (k + 0.5) / n, phi = kPi * (1.0 + std::sqrt(5.0)) * (k + 0.5);
        d.push_back({std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z});
    }
    const double elevations[] = {-10, -8, -6, -4, -3, -2, -1, 0, 1, 2, 4, 6, 10, 20, 45, 90};
    const double altitudes[] = {0.0, 1000.0, 3000.0, 10000.0};
    FILE* spectra = std::fopen((dir + "/spectra.f32").c_str(), "wb");
    FILE* sun = std::fopen((dir + "/sun.f32").c_str(), "wb");
    FILE* cases = std::fopen((dir + "/cases.txt").c_str(), "w");
    FILE* presets = std::fopen((dir + "/presets.txt").c_str(), "w");
    if (!spectra || !sun || !cases || !presets) {
        std::fprintf(stderr, "cannot write into %s\n", dir.c_str());
        return 1;
    }
    const LutSky lut(SkyOptions{}, nullptr);
    int index = 0;
    for (const std::string& p : Atmosphere::preset_names()) {
        std::fprintf(presets, "%s\n", p.c_str());
        const Atmosphere atm = Atmosphere::preset(p, wl);
        for (double e : elevations)
            for (double a : altitudes) {
                const double er = e * kPi / 180.0;
                const Observer o{a, {std::cos(er), 0.0, std::sin(er)}};
                std::vector<float> out(d.size() * wl.size());
                lut.radiance(atm, o, d, out);
                std::fwrite(out.data(), sizeof(float), out.size(), spectra);
                const SunRadiometry s = sun_radiometry(atm, o);
                const std::vector<float> direct(s.direct_irradiance.begin(), s.direct_irradiance.end());
                std::fwrite(direct.data(), sizeof(float), direct.size(), sun);
                std::fprintf(cases, "%d %g %g\n", index, e, a);
            }
        ++index;
    }
    std::fclose(spectra);
    std::fclose(sun);
    std::fclose(cases);
    std::fclose(presets);
    FILE* m = std::fopen((dir + "/cie48.txt").c_str(), "w");
    // The conversion is named: a range-for over a temporary's member would dangle.
    const SpectrumToRgb cie48(wl);
    for (double v : cie48.matrix()) std::fprintf(m, "%.12g\n", v);
    std::fclose(m);
    // Bruneton 2017's three-sample sky conversion (the default before the fitted four).
    m = std::fopen((dir + "/bruneton3.txt").c_str(), "w");
    const SpectrumToRgb bruneton3(std::vector<double>{680.0, 550.0, 440.0});
    for (double v : bruneton3.matrix()) std::fprintf(m, "%.12g\n", v);
    std::fclose(m);
    return 0;
}
