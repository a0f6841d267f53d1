// SPDX-License-Identifier: Apache-2.0
// Gamut mapping (color/gamut.hpp) against its definition: luminance kept, the chromaticity
// on the line from the white point through the input (the dominant wavelength kept), the
// nearest channel brought exactly to 0, in-gamut colours untouched; and the aerosol's
// optical depth and turbidity (atmosphere/aerosol.hpp) against closed forms.
#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "welkin/atmosphere/aerosol.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/rng.hpp"
#include "welkin/color/gamut.hpp"

using namespace welkin;

namespace {

// Rec.709's RGB -> XYZ (IEC 61966-2-1), for chromaticities.
constexpr std::array<double, 9> kRec709ToXyz = {0.4124, 0.3576, 0.1805, 0.2126, 0.7152,
                                                0.0722, 0.0193, 0.1192, 0.9505};
// Its luminance weights (the Y row), as SpectrumToRgb gives them for Rec.709 output.
constexpr std::array<double, 3> kRec709Luminance = luminance_weights(kRec709ToXyz);
// ACEScg (AP1, D60; SMPTE ST 2065-1 / Academy S-2014-004): another space's weights.
constexpr std::array<double, 3> kAcesCgLuminance = {0.2722287168, 0.6740817658, 0.0536895174};

std::array<double, 3> xyz(const std::array<double, 3>& c) {
    const auto& m = kRec709ToXyz;
    return {m[0] * c[0] + m[1] * c[1] + m[2] * c[2], m[3] * c[0] + m[4] * c[1] + m[5] * c[2],
            m[6] * c[0] + m[7] * c[1] + m[8] * c[2]};
}

std::array<double, 2> xy(const std::array<double, 3>& c) {
    const auto t = xyz(c);
    return {t[0] / (t[0] + t[1] + t[2]), t[1] / (t[0] + t[1] + t[2])};
}

double dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

}  // namespace

TEST(Gamut, InGamutColoursAreUntouched) {
    for (const std::array<double, 3> c :
         {std::array<double, 3>{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}, {0.0, 5.0, 0.1}})
        EXPECT_EQ(gamut_map(c, kRec709Luminance), c);
}

TEST(Gamut, KeepsLuminanceAndDominantWavelength) {
    PathRng rng(7, 0, 0);
    const std::array<double, 2> white = xy({1.0, 1.0, 1.0});
    for (const auto& w : {kRec709Luminance, kAcesCgLuminance}) {
        int mapped = 0, hue_checked = 0;
        for (int n = 0; n < 20000; ++n) {
            const std::array<double, 3> c = {4.0 * rng.uniform() - 1.0, 4.0 * rng.uniform() - 1.0,
                                             4.0 * rng.uniform() - 1.0};
            const std::array<double, 3> m = gamut_map(c, w);
            const double y = dot(w, c);
            ASSERT_GE(std::min({m[0], m[1], m[2]}), 0.0);
            if (!(y > 0.0)) {
                EXPECT_EQ(m, (std::array<double, 3>{0.0, 0.0, 0.0}));
                continue;
            }
            EXPECT_NEAR(dot(w, m), y, 1e-12 * std::max(1.0, y));
            if (std::min({c[0], c[1], c[2]}) >= 0.0) continue;
            ++mapped;
            EXPECT_NEAR(std::min({m[0], m[1], m[2]}), 0.0, 1e-12);  // on the gamut's boundary
            // Chromaticity (Rec.709's), for colours a spectrum can have (X, Y, Z >= 0; an
            // RGB triple with a negative X or Z has no chromaticity on the white's side).
            const auto t = xyz(c);
            if (w != kRec709Luminance || std::min({t[0], t[1], t[2]}) < 0.0) continue;
            // The mapped chromaticity lies between the white point and the input's, on one line.
            const auto a = xy(c), b = xy(m);
            const double cross =
                (a[0] - white[0]) * (b[1] - white[1]) - (a[1] - white[1]) * (b[0] - white[0]);
            const double along =
                (a[0] - white[0]) * (b[0] - white[0]) + (a[1] - white[1]) * (b[1] - white[1]);
            EXPECT_NEAR(cross, 0.0, 1e-9);
            EXPECT_GE(along, 0.0);
            ++hue_checked;
        }
        EXPECT_GT(mapped, 1000);
        if (w == kRec709Luminance) {
            EXPECT_GT(hue_checked, 200);
        }
    }
}

TEST(Gamut, FloatTriplesInPlaceAndNonFiniteLeftForTheCaller) {
    float px[9] = {-0.1f, 0.5f, 1.0f, 1.0f, 1.0f, 1.0f, NAN, 1.0f, -1.0f};
    gamut_map(px, 3, kRec709Luminance);
    EXPECT_GE(std::min({px[0], px[1], px[2]}), 0.0f);
    EXPECT_NEAR(0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2], 0.2126 * -0.1 + 0.7152 * 0.5 + 0.0722,
                1e-6);
    EXPECT_EQ(px[3], 1.0f);
    EXPECT_TRUE(std::isnan(px[6]));
}

TEST(Aerosol, OpticalDepthOfAnExponentialIsItsClosedForm) {
    // tau(lambda) = beta(lambda) H (1 - exp(-top / H)) for a single exponential; bruneton2017's
    // aerosol is grey, so every wavelength gives 5.328e-3 (1 - exp(-50)).
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    EXPECT_NEAR(aerosol_optical_depth(atm, 550.0), 5.328e-3 * (1.0 - std::exp(-60e3 / 1200.0)), 1e-9);
    EXPECT_NEAR(aerosol_optical_depth(atm, 400.0), 5.328e-3, 1e-9);
}

TEST(Aerosol, PresetsHaveTheirOpacColumnsAndTheDefaultIsAClearDay) {
    const std::pair<const char*, double> want[] = {{"clear_day", 0.12},    {"clear", 0.064},
                                                   {"hazy", 0.327},        {"polluted", 0.643},
                                                   {"desert_dust", 0.286}, {"maritime", 0.096}};
    // Exact where 550 nm is a channel (the spectral grid); between the default channels (480
    // and 560 nm) the log-log interpolation misses the kink of OPAC's two Angstrom exponents
    // at 500 nm by a fraction of a per cent.
    for (const auto& [name, tau] : want) {
        EXPECT_NEAR(aerosol_optical_depth(Atmosphere::preset(name, spectral_wavelengths_nm()), 550.0), tau,
                    1e-6 * tau)
            << name;
        EXPECT_NEAR(aerosol_optical_depth(Atmosphere::preset(name), 550.0), tau, 5e-3 * tau) << name;
    }
    const double d = aerosol_optical_depth(Atmosphere::preset(kDefaultPreset), 550.0);
    EXPECT_GE(d, 0.08);
    EXPECT_LE(d, 0.15);
    EXPECT_EQ(Atmosphere::preset_names().front(), kDefaultPreset);
}

TEST(Aerosol, SetOpticalDepthScalesTheColumnOnly) {
    Atmosphere atm = Atmosphere::preset("hazy");
    const Atmosphere before = atm;
    set_aerosol_optical_depth(atm, 0.2);
    EXPECT_NEAR(aerosol_optical_depth(atm, 550.0), 0.2, 1e-12);
    for (std::size_t c = 0; c < atm.channels(); ++c)
        EXPECT_NEAR(atm.mie_scattering[c] / atm.mie_extinction[c],
                    before.mie_scattering[c] / before.mie_extinction[c], 1e-15);
    EXPECT_THROW(set_aerosol_optical_depth(atm, 11.0), InvalidArgument);
    EXPECT_THROW(set_aerosol_optical_depth(atm, std::nan("")), InvalidArgument);
    // Preetham et al. 1999, Appendix A.2: beta = 0.04608 T - 0.04586, tau = beta 0.55^-1.3.
    EXPECT_NEAR(preetham_turbidity_to_aerosol_optical_depth(2.0), 0.0463 * std::pow(0.55, -1.3), 1e-4);
    EXPECT_THROW(preetham_turbidity_to_aerosol_optical_depth(0.5), InvalidArgument);
}
