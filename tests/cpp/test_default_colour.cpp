// SPDX-License-Identifier: Apache-2.0
// The default fast path's colour against the 48-wavelength spectral path: the default
// four wavelengths with their fitted conversion (color.cpp) and the spectral path at
// 360..830 nm through the CIE functions, both computed here by the lut method, over the
// upper hemisphere, for every preset, observers on the ground and 5 km up (alternately),
// the sun from 8 degrees below the horizon to high in the sky. The directions are not those of the
// fit (color.cpp: a Fibonacci spiral of 160), so this checks the fit on views it was not
// fitted to. Tolerances: CIE 1931 xy within 0.005 at the median and 0.015 at worst;
// luminance within 2 % at the median.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"
#include "welkin/sky/lut.hpp"

using namespace welkin;

namespace {

// Rec.709 -> XYZ (IEC 61966-2-1), and the chromaticity.
std::array<double, 3> xyz_of(const float* rgb) {
    const double r = rgb[0], g = rgb[1], b = rgb[2];
    return {0.4124564 * r + 0.3575761 * g + 0.1804375 * b, 0.2126729 * r + 0.7151522 * g + 0.0721750 * b,
            0.0193339 * r + 0.1191920 * g + 0.9503041 * b};
}

struct Errors {
    std::vector<double> xy, luminance;
};

// Colour errors of the default path against the spectral path, for suns at (elevation in
// degrees, observer altitude in m).
Errors colour_errors(const std::vector<std::pair<double, double>>& suns) {
    const int n = 7 * 12;  // 7 elevations x 12 azimuths over the upper hemisphere
    std::vector<glm::dvec3> dirs;
    for (int a = 0; a < 7; ++a)
        for (int b = 0; b < 12; ++b) {
            const double e = kPi / 2 * (a + 0.25) / 7.0, phi = kTwoPi * (b + 0.3) / 12.0;
            dirs.push_back({std::cos(e) * std::cos(phi), std::cos(e) * std::sin(phi), std::sin(e)});
        }
    const LutSky lut(SkyOptions{}, nullptr);
    Errors out;
    for (const std::string& preset : Atmosphere::preset_names()) {
        const Atmosphere fast = Atmosphere::preset(preset);
        const Atmosphere spectral = Atmosphere::preset(preset, spectral_wavelengths_nm());
        const SpectrumToRgb fast_rgb(fast.wavelengths_nm), spectral_rgb(spectral.wavelengths_nm);
        for (const auto& [elev, altitude] : suns) {
            const double er = elev * kPi / 180.0;
            const Observer o{altitude, {std::cos(er), 0.0, std::sin(er)}};
            std::vector<float> a(n * fast.channels()), b(n * spectral.channels());
            lut.radiance(fast, o, dirs, a);
            lut.radiance(spectral, o, dirs, b);
            std::vector<float> ra(n * 3), rb(n * 3);
            fast_rgb.convert(a, ra);
            spectral_rgb.convert(b, rb);
            for (int k = 0; k < n; ++k) {
                const auto xa = xyz_of(&ra[3 * k]), xb = xyz_of(&rb[3 * k]);
                const double sa = xa[0] + xa[1] + xa[2], sb = xb[0] + xb[1] + xb[2];
                EXPECT_GT(sb, 0.0);
                out.xy.push_back(std::hypot(xa[0] / sa - xb[0] / sb, xa[1] / sa - xb[1] / sb));
                out.luminance.push_back(std::abs(xa[1] / xb[1] - 1.0));
            }
        }
    }
    return out;
}

double median(std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

}  // namespace

TEST(DefaultColour, TwilightMatchesTheSpectralPath) {
    const Errors e = colour_errors({{-8.0, 0.0}, {-5.0, 5000.0}, {-2.0, 0.0}, {0.5, 5000.0}});
    EXPECT_LE(median(e.xy), 0.005);
    EXPECT_LE(*std::max_element(e.xy.begin(), e.xy.end()), 0.015);
    EXPECT_LE(median(e.luminance), 0.02);
}

TEST(DefaultColour, DaylightMatchesTheSpectralPath) {
    const Errors e = colour_errors({{3.0, 5000.0}, {15.0, 0.0}, {50.0, 5000.0}, {85.0, 0.0}});
    EXPECT_LE(median(e.xy), 0.005);
    EXPECT_LE(*std::max_element(e.xy.begin(), e.xy.end()), 0.015);
    EXPECT_LE(median(e.luminance), 0.02);
}

// The three-wavelength path that the default replaced misses twilight by far more: the
// test above can fail for the right reason.
TEST(DefaultColour, ThreeWavelengthsMissTwilight) {
    const Atmosphere three = Atmosphere::preset("clear", {680.0, 550.0, 440.0});
    const Atmosphere spectral = Atmosphere::preset("clear", spectral_wavelengths_nm());
    const LutSky lut(SkyOptions{}, nullptr);
    const Observer o{0.0, {std::cos(-0.105), 0.0, std::sin(-0.105)}};  // sun 6 degrees down
    const std::vector<glm::dvec3> zenith{{0.0, 0.0, 1.0}};
    std::vector<float> a(3), b(spectral.channels()), ra(3), rb(3);
    lut.radiance(three, o, zenith, a);
    lut.radiance(spectral, o, zenith, b);
    SpectrumToRgb(three.wavelengths_nm).convert(a, ra);
    SpectrumToRgb(spectral.wavelengths_nm).convert(b, rb);
    const auto xa = xyz_of(ra.data()), xb = xyz_of(rb.data());
    const double sa = xa[0] + xa[1] + xa[2], sb = xb[0] + xb[1] + xb[2];
    EXPECT_GT(std::hypot(xa[0] / sa - xb[0] / sb, xa[1] / sa - xb[1] / sb), 0.02);
}
