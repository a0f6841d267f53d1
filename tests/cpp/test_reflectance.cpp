// SPDX-License-Identifier: Apache-2.0
// RGB -> reflectance spectrum (color/reflectance.hpp) checked through the engine's other
// colour path: the spectrum, sampled at the spectral mode's 48 wavelengths, converted by
// SpectrumToRgb (CIE 1931 integration at 10 nm, color.hpp) and divided by the flat white
// reflector's conversion, gives back the asked colour; greys are flat; every value is a
// reflectance; a colour no reflectance has keeps its hue; bad input names the parameter.
//
// Tolerance: 0.004 per channel for colours inside the object-colour solid (the fit itself
// reaches 1e-6 on its 1 nm grid; the rest is the 10 nm sampling of the check).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/reflectance.hpp"

using namespace welkin;

namespace {

// The colour of a reflectance through SpectrumToRgb: rgb(R) / rgb(1), channel by channel.
std::array<double, 3> colour_through_spectrum_to_rgb(const std::vector<double>& r,
                                                     const std::vector<double>& w, ColorSpace space) {
    const SpectrumToRgb to_rgb(w, -3.0, space);
    const std::vector<float> rf(r.begin(), r.end()), ones(w.size(), 1.0f);
    const auto c = to_rgb.convert(rf), white = to_rgb.convert(ones);
    return {c[0] / white[0], c[1] / white[1], c[2] / white[2]};
}

// Muted and mid-saturated colours (linear), the range of natural ground: soil, grass, sand,
// rock, snow, a painted surface.
const std::vector<std::array<double, 3>> kColours = {
    {0.20, 0.12, 0.06}, {0.05, 0.10, 0.03}, {0.45, 0.38, 0.25}, {0.30, 0.30, 0.32}, {0.80, 0.82, 0.85},
    {0.10, 0.20, 0.40}, {0.60, 0.20, 0.15}, {0.25, 0.45, 0.20}, {0.50, 0.50, 0.10}, {0.02, 0.02, 0.02},
};

}  // namespace

TEST(Reflectance, ColourComesBackThroughTheSpectralConversion) {
    const std::vector<double> w = spectral_wavelengths_nm(10.0);
    for (ColorSpace space : {ColorSpace::Rec709, ColorSpace::Rec2020, ColorSpace::Acescg}) {
        for (const auto& c : kColours) {
            const std::vector<double> r = rgb_to_reflectance(c, w, space);
            const auto back = colour_through_spectrum_to_rgb(r, w, space);
            const auto own = reflectance_to_rgb(r, w, space);
            for (int k = 0; k < 3; ++k) {
                EXPECT_NEAR(back[k], c[k], 0.004) << color_space_name(space) << " colour " << c[0] << " "
                                                  << c[1] << " " << c[2] << " channel " << k;
                EXPECT_NEAR(own[k], c[k], 0.002) << color_space_name(space) << " channel " << k;
            }
        }
    }
}

TEST(Reflectance, GreysAreFlatAndEveryValueIsAReflectance) {
    const std::vector<double> w = spectral_wavelengths_nm(10.0);
    for (double g : {0.0, 0.1, 0.5, 1.0}) {
        const std::vector<double> r = rgb_to_reflectance({g, g, g}, w);
        for (double v : r) EXPECT_EQ(v, g);
    }
    for (const auto& c : kColours) {
        const std::vector<double> r = rgb_to_reflectance(c, w);
        for (double v : r) {
            EXPECT_GT(v, 0.0);
            EXPECT_LT(v, 1.0);
        }
    }
}

TEST(Reflectance, SaturatedPrimariesKeepTheirHue) {
    // Full-value primaries lie outside (or on) the object-colour solid: the nearest
    // sigmoid keeps the primary's channel the largest by far.
    const std::vector<double> w = spectral_wavelengths_nm(10.0);
    for (int p = 0; p < 3; ++p) {
        std::array<double, 3> c{0.0, 0.0, 0.0};
        c[p] = 1.0;
        const std::vector<double> r = rgb_to_reflectance(c, w);
        for (double v : r) ASSERT_TRUE(v >= 0.0 && v <= 1.0);
        const auto back = reflectance_to_rgb(r, w);
        for (int k = 0; k < 3; ++k) {
            if (k != p) {
                EXPECT_LT(back[k], 0.5 * back[p]) << "primary " << p << " channel " << k;
            }
        }
        EXPECT_GT(back[p], 0.5) << "primary " << p;
    }
}

TEST(Reflectance, AtTheDefaultWavelengthsTheSpectrumIsSampled) {
    // The default atmosphere's four wavelengths get the same smooth spectrum's values.
    const std::vector<double> dense = spectral_wavelengths_nm(10.0);
    const std::vector<double> four{620.0, 560.0, 480.0, 440.0};
    const std::array<double, 3> c{0.45, 0.30, 0.15};
    const std::vector<double> r4 = rgb_to_reflectance(c, four), r = rgb_to_reflectance(c, dense);
    for (std::size_t i = 0; i < four.size(); ++i) {
        const auto at = std::find(dense.begin(), dense.end(), four[i]);
        ASSERT_NE(at, dense.end());
        EXPECT_NEAR(r4[i], r[std::size_t(at - dense.begin())], 1e-12);
    }
    EXPECT_GT(r4[0], r4[3]);  // an orange-brown reflects more red than blue
}

TEST(Reflectance, BadInputNamesTheParameter) {
    const std::vector<double> w{550.0};
    EXPECT_EQ(test::parameter_of([&] { rgb_to_reflectance({1.5, 0.1, 0.1}, w); }), "ground_color");
    EXPECT_EQ(test::parameter_of([&] { rgb_to_reflectance({-0.1, 0.1, 0.1}, w); }), "ground_color");
    EXPECT_EQ(test::parameter_of([&] { rgb_to_reflectance({NAN, 0.1, 0.1}, w); }), "ground_color");
    EXPECT_EQ(test::parameter_of([&] {
                  rgb_to_reflectance({0.2, 0.1, 0.1}, std::vector<double>{});
              }),
              "wavelengths_nm");
    EXPECT_EQ(
        test::parameter_of([&] { reflectance_to_rgb(std::vector<double>{0.1}, std::vector<double>{}); }),
        "reflectance");
}
