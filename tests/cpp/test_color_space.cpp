// SPDX-License-Identifier: Apache-2.0
// The output colour spaces (color_space.hpp): their matrices against published ones,
// white to white, primaries to unit vectors, and the spectrum conversion in each space.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "welkin/base/error.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/color_space.hpp"

namespace welkin {
namespace {

void expect_near(const Matrix3& got, const Matrix3& want, double tol, const char* what) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            EXPECT_NEAR(got[i][j], want[i][j], tol) << what << " [" << i << "][" << j << "]";
}

constexpr ColorSpace kSpaces[] = {ColorSpace::Rec709, ColorSpace::Rec2020, ColorSpace::Acescg};

TEST(ColorSpace, NamesRoundTripAndBadNamesAreRejected) {
    for (ColorSpace s : kSpaces) EXPECT_EQ(color_space_from_name(color_space_name(s)), s);
    try {
        color_space_from_name("srgb");
        FAIL() << "no exception";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("color_space"), std::string::npos) << e.what();
    }
}

TEST(ColorSpace, Rec709PrimariesGiveThePublishedMatrix) {
    // RP 177 from BT.709's chromaticities against the IEC 61966-2-1 matrix, four decimals
    // as published: within 4e-4, the published matrix's own rounding (its [1][0] reads
    // -0.9689 where the primaries give -0.96924; every other entry is within 1e-4).
    const Matrix3 from_primaries = inverse(rgb_to_xyz_matrix(chromaticities(ColorSpace::Rec709)));
    expect_near(from_primaries, xyz_to_rgb_matrix(ColorSpace::Rec709), 4e-4, "Rec.709");
}

TEST(ColorSpace, Rec2020MatchesBt2087AndBt2020Luminance) {
    // ITU-R BT.2087-0, eq. (4): the BT.2020 RGB -> XYZ matrix (four decimals); its Y row is
    // BT.2020's own luminance coefficients (Table 4: 0.2627, 0.6780, 0.0593).
    const Matrix3 published = {
        {{0.6370, 0.1446, 0.1689}, {0.2627, 0.6780, 0.0593}, {0.0000, 0.0281, 1.0610}}};
    expect_near(rgb_to_xyz_matrix(chromaticities(ColorSpace::Rec2020)), published, 6e-5, "BT.2020 NPM");
    expect_near(inverse(xyz_to_rgb_matrix(ColorSpace::Rec2020)), published, 6e-5, "XYZ -> BT.2020");
}

TEST(ColorSpace, Ap1MatchesTheAcademysMatrix) {
    // Academy S-2014-004 (ACEScg), sec. 4.1.2: AP1 -> XYZ with the ACES white, ten decimals.
    const Matrix3 published = {{{0.6624541811, 0.1340042065, 0.1561876870},
                                {0.2722287168, 0.6740817658, 0.0536895174},
                                {-0.0055746495, 0.0040607335, 1.0103391003}}};
    expect_near(rgb_to_xyz_matrix(chromaticities(ColorSpace::Acescg)), published, 1e-9, "AP1 NPM");
}

TEST(ColorSpace, Rec709ToAcescgMatchesTheBradfordMatrixOfAcesConfigs) {
    // Linear sRGB -> ACEScg with Bradford D65 -> ACES white, as the ACES OpenColorIO configs
    // and colour-science publish it ("Utility - Linear - sRGB"); the tolerance covers the
    // four-decimal IEC matrix here against BT.709's exact primaries there.
    const Matrix3 published = {{{0.6130974, 0.3395231, 0.0473794},
                                {0.0701937, 0.9163539, 0.0134523},
                                {0.0206156, 0.1095698, 0.8698151}}};
    expect_near(rgb_to_rgb_matrix(ColorSpace::Rec709, ColorSpace::Acescg), published, 3e-4, "709 -> ACEScg");
}

TEST(ColorSpace, WhiteStaysWhiteAndPrimariesAreUnitVectors) {
    for (ColorSpace to : kSpaces) {
        const auto white = mat_vec(rgb_to_rgb_matrix(ColorSpace::Rec709, to), {1.0, 1.0, 1.0});
        for (double c : white) EXPECT_NEAR(c, 1.0, 2e-4) << color_space_name(to);
        // Each primary's XYZ (in the space's own white) is a unit vector of the space.
        const Chromaticities ch = chromaticities(to);
        const Matrix3 to_rgb = inverse(rgb_to_xyz_matrix(ch));
        const std::array<double, 2> primaries[3] = {ch.red, ch.green, ch.blue};
        for (int k = 0; k < 3; ++k) {
            const auto& xy = primaries[k];
            const auto rgb = mat_vec(to_rgb, {xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]});
            for (int j = 0; j < 3; ++j) {
                if (j != k) {
                    EXPECT_NEAR(rgb[j], 0.0, 1e-12) << color_space_name(to) << " primary " << k;
                }
            }
            EXPECT_GT(rgb[k], 0.0);
        }
    }
}

TEST(ColorSpace, RoundTripsAndBradfordKeepsIdentity) {
    for (ColorSpace a : kSpaces)
        for (ColorSpace b : kSpaces) {
            const Matrix3 there_and_back = multiply(rgb_to_rgb_matrix(b, a), rgb_to_rgb_matrix(a, b));
            expect_near(there_and_back, {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}, 1e-12, "round trip");
        }
    expect_near(bradford_adaptation({0.3127, 0.3290}, {0.3127, 0.3290}), {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
                1e-12, "Bradford D65 -> D65");
}

TEST(ColorSpace, SpectrumConversionIsTheSameXyzThroughEachMatrix) {
    // Every path (many wavelengths, the fitted four, Bruneton's three): the space's RGB is
    // the Rec.709 RGB's XYZ through the space's matrix, and the luminance row agrees.
    const std::vector<std::vector<double>> sets = {
        {400, 450, 500, 550, 600, 650, 700}, {440, 480, 560, 620}, {440, 550, 680}};
    for (const auto& w : sets)
        for (double p : {-3.0, 0.0}) {
            const SpectrumToRgb rec709(w, p);
            for (ColorSpace s : kSpaces) {
                const SpectrumToRgb conv(w, p, s);
                EXPECT_EQ(conv.space(), s);
                const Matrix3 m = rgb_to_rgb_matrix(ColorSpace::Rec709, s);
                const std::size_t n = w.size();
                for (std::size_t c = 0; c < n; ++c)
                    for (int j = 0; j < 3; ++j) {
                        const auto& a = rec709.matrix();
                        const double want = m[j][0] * a[c] + m[j][1] * a[n + c] + m[j][2] * a[2 * n + c];
                        EXPECT_NEAR(conv.matrix()[j * n + c], want, 1e-9 * (1.0 + std::abs(want)));
                    }
            }
        }
}

TEST(ColorSpace, SaturatedSpectrumIsOutsideRec709ButInsideRec2020) {
    // A band of 510-560 nm (a saturated green near xy (0.2, 0.72): outside Rec.709's
    // gamut, inside Rec.2020's and AP1's): negative red in Rec.709, all channels >= 0 in
    // Rec.2020 and ACEScg.
    std::vector<double> w;
    std::vector<float> spectrum;
    for (double l = 400; l <= 700; l += 5) {
        w.push_back(l);
        spectrum.push_back(l >= 510.0 && l <= 560.0 ? 1.0f : 0.0f);
    }
    // The matrix alone (before convert's gamut mapping, gamut.hpp), row j times the spectrum.
    const auto raw = [&](const SpectrumToRgb& to_rgb) {
        std::array<double, 3> rgb{};
        for (std::size_t j = 0; j < 3; ++j)
            for (std::size_t c = 0; c < w.size(); ++c)
                rgb[j] += to_rgb.matrix()[j * w.size() + c] * spectrum[c];
        return rgb;
    };
    const SpectrumToRgb rec709(w, -3.0, ColorSpace::Rec709);
    EXPECT_LT(raw(rec709)[0], 0.0);
    for (double c : rec709.convert(spectrum)) EXPECT_GE(c, 0.0);  // mapped into the gamut
    for (ColorSpace s : {ColorSpace::Rec2020, ColorSpace::Acescg}) {
        const SpectrumToRgb to_rgb(w, -3.0, s);
        const auto inside = raw(to_rgb), converted = to_rgb.convert(spectrum);
        for (int j = 0; j < 3; ++j) {
            EXPECT_GE(inside[j], 0.0) << color_space_name(s);
            EXPECT_NEAR(converted[j], inside[j], 1e-12 * std::abs(inside[j]) + 1e-15) << color_space_name(s);
        }
    }
}

}  // namespace
}  // namespace welkin
