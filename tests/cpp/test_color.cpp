// SPDX-License-Identifier: Apache-2.0
// Colour conversion: the CIE fit against the CIE table, closed-form consistency of the two
// conversion paths, and the three-sample conversion against the peer's spectral RGB.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/spectral_data.hpp"

using namespace welkin;

namespace {

// CIE 1931 2-degree colour-matching functions, every 10 nm from 360 to 830 nm
// (CIE 015:2004; the CVRL table ciexyz31.txt, as in Bruneton's atmosphere/constants.h).
struct CieRow {
    double nm, x, y, z;
};
const std::vector<CieRow>& cie1931_table() {
    static const std::vector<CieRow> t = {
        {360, 0.0001299, 0.000003917, 0.0006061},
        {370, 0.0004149, 0.00001239, 0.001946},
        {380, 0.001368, 0.000039, 0.006450001},
        {390, 0.004243, 0.00012, 0.02005001},
        {400, 0.01431, 0.000396, 0.06785001},
        {410, 0.04351, 0.00121, 0.2074},
        {420, 0.13438, 0.004, 0.6456},
        {430, 0.2839, 0.0116, 1.3856},
        {440, 0.34828, 0.023, 1.74706},
        {450, 0.3362, 0.038, 1.77211},
        {460, 0.2908, 0.06, 1.6692},
        {470, 0.19536, 0.09098, 1.28764},
        {480, 0.09564, 0.13902, 0.8129501},
        {490, 0.03201, 0.20802, 0.46518},
        {500, 0.0049, 0.323, 0.272},
        {510, 0.0093, 0.503, 0.1582},
        {520, 0.06327, 0.71, 0.07824999},
        {530, 0.1655, 0.862, 0.04216},
        {540, 0.2904, 0.954, 0.0203},
        {550, 0.4334499, 0.9949501, 0.008749999},
        {560, 0.5945, 0.995, 0.0039},
        {570, 0.7621, 0.952, 0.0021},
        {580, 0.9163, 0.87, 0.001650001},
        {590, 1.0263, 0.757, 0.0011},
        {600, 1.0622, 0.631, 0.0008},
        {610, 1.0026, 0.503, 0.00034},
        {620, 0.8544499, 0.381, 0.00019},
        {630, 0.6424, 0.265, 0.00004999999},
        {640, 0.4479, 0.175, 0.00002},
        {650, 0.2835, 0.107, 0.0},
        {660, 0.1649, 0.061, 0.0},
        {670, 0.0874, 0.032, 0.0},
        {680, 0.04677, 0.017, 0.0},
        {690, 0.0227, 0.00821, 0.0},
        {700, 0.01135916, 0.004102, 0.0},
        {710, 0.005790346, 0.002091, 0.0},
        {720, 0.002899327, 0.001047, 0.0},
        {730, 0.001439971, 0.00052, 0.0},
        {740, 0.0006900786, 0.0002492, 0.0},
        {750, 0.0003323011, 0.00012, 0.0},
        {760, 0.0001661505, 0.00006, 0.0},
        {770, 0.00008307527, 0.00003, 0.0},
        {780, 0.00004150994, 0.00001499, 0.0},
        {790, 0.00002067383, 0.0000074657, 0.0},
        {800, 0.00001025398, 0.0000037029, 0.0},
        {810, 0.000005085868, 0.0000018366, 0.0},
        {820, 0.000002522525, 0.00000091093, 0.0},
        {830, 0.000001251141, 0.00000045181, 0.0},
    };
    return t;
}

// The table, linearly interpolated (what the peer does at 1 nm from its 5 nm table).
Xyz cie_table_at(double nm) {
    const auto& t = cie1931_table();
    if (nm <= t.front().nm) return {t.front().x, t.front().y, t.front().z};
    if (nm >= t.back().nm) return {t.back().x, t.back().y, t.back().z};
    const std::size_t i = std::size_t((nm - 360.0) / 10.0);
    const double f = (nm - t[i].nm) / 10.0;
    return {t[i].x + f * (t[i + 1].x - t[i].x), t[i].y + f * (t[i + 1].y - t[i].y),
            t[i].z + f * (t[i + 1].z - t[i].z)};
}

// Inverse of a 3 x 3 matrix (row-major).
std::array<double, 9> inverse3(const std::array<double, 9>& m) {
    const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                       m[2] * (m[3] * m[7] - m[4] * m[6]);
    return {(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det,
            (m[1] * m[5] - m[2] * m[4]) / det, (m[5] * m[6] - m[3] * m[8]) / det,
            (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
            (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det,
            (m[0] * m[4] - m[1] * m[3]) / det};
}

const std::array<double, 9> kXyzToRgb = {3.2406, -1.5372, -0.4986, -0.9689, 1.8758,
                                         0.0415, 0.0557,  -0.2040, 1.0570};

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

TEST(Color, FitFollowsTheCie1931Table) {
    // The multi-lobe fit of Wyman et al. 2013, measured at the table's 10 nm points:
    // worst |fit - table| = 0.0146 (xbar, 630 nm), 0.0070 (ybar), 0.0129 (zbar, 440 nm),
    // i.e. 1.4 %, 0.7 % and 0.7 % of each function's peak (1.062, 1.0, 1.783). Asserted:
    // 1.5 % of the peak.
    double worst[3] = {0, 0, 0};
    for (const CieRow& row : cie1931_table()) {
        const Xyz f = cie1931_cmf(row.nm);
        worst[0] = std::max(worst[0], std::abs(f.x - row.x));
        worst[1] = std::max(worst[1], std::abs(f.y - row.y));
        worst[2] = std::max(worst[2], std::abs(f.z - row.z));
    }
    std::printf("fit vs CIE table, worst abs error: x %.4f  y %.4f  z %.4f\n", worst[0], worst[1], worst[2]);
    EXPECT_LT(worst[0], 0.015 * 1.0622);
    EXPECT_LT(worst[1], 0.015 * 1.0);
    EXPECT_LT(worst[2], 0.015 * 1.7826);
    // Spot values named in the CIE table.
    EXPECT_NEAR(cie1931_cmf(555.0).y, 1.0, 0.005);
    EXPECT_NEAR(cie1931_cmf(600.0).x, 1.0622, 0.01);
}

TEST(Color, FitIntegralsMatchTheTable) {
    // The CIE functions are scaled so that their integrals are equal (equal-energy white
    // E has x = y = z): 106.86 nm for ybar over 360..830 nm (sum of the 1 nm table).
    double fit[3] = {0, 0, 0}, table[3] = {0, 0, 0};
    for (double nm = 360.0; nm <= 830.0; nm += 0.5) {
        const double w = (nm == 360.0 || nm == 830.0) ? 0.25 : 0.5;
        const Xyz f = cie1931_cmf(nm), t = cie_table_at(nm);
        fit[0] += w * f.x, fit[1] += w * f.y, fit[2] += w * f.z;
        table[0] += w * t.x, table[1] += w * t.y, table[2] += w * t.z;
    }
    std::printf("integrals, fit: %.3f %.3f %.3f   table: %.3f %.3f %.3f nm\n", fit[0], fit[1], fit[2],
                table[0], table[1], table[2]);
    EXPECT_NEAR(table[1], 106.86, 0.2);  // the interpolated 10 nm table itself
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(fit[k] / table[k], 1.0, 0.01) << k;
}

TEST(Color, EqualEnergyWhiteIsAchromaticThroughTheSpectralPath) {
    const std::vector<double> w = spectral_wavelengths_nm();
    ASSERT_EQ(w.size(), 48u);
    const SpectrumToRgb conv(w);
    const std::vector<float> flat(w.size(), 1.0f);
    const std::array<double, 3> rgb = conv.convert(flat);
    // Back to XYZ with the inverse matrix; E's chromaticity is (1/3, 1/3).
    const std::array<double, 9> inv = inverse3(kXyzToRgb);
    const double X = inv[0] * rgb[0] + inv[1] * rgb[1] + inv[2] * rgb[2];
    const double Y = inv[3] * rgb[0] + inv[4] * rgb[1] + inv[5] * rgb[2];
    const double Z = inv[6] * rgb[0] + inv[7] * rgb[1] + inv[8] * rgb[2];
    const double s = X + Y + Z;
    std::printf("E white: X %.3f Y %.3f Z %.3f  x %.4f y %.4f\n", X, Y, Z, X / s, Y / s);
    EXPECT_NEAR(X / s, 1.0 / 3.0, 0.01);
    EXPECT_NEAR(Y / s, 1.0 / 3.0, 0.01);
    EXPECT_NEAR(Y, 106.86, 0.01 * 106.86);  // L = 1 over 360..830 nm
}

TEST(Color, ThreeSampleConversionIsExactForItsOwnSpectrumModel) {
    // Bruneton's approximation assumes L(lambda) = L(lambda_j) E(lambda)/E(lambda_j)
    // (lambda/lambda_j)^p around each sample. For a spectrum that IS E(lambda) lambda^p, the
    // three samples must give the full spectral conversion of that spectrum. What differs
    // is only quadrature: the spectral path integrates the linear interpolant of the
    // 48 samples (10 nm), the three-sample path E's 10 nm table times the exact power
    // law at 1 nm. Measured difference < 0.1 %; asserted 0.3 %.
    const std::vector<double> w3 = test::kPeerWavelengthsNm;
    const std::vector<double> w48 = spectral_wavelengths_nm();
    for (double p : {-4.0, -3.0, 0.0}) {
        auto spectrum = [p](double nm) {
            return float(solar_irradiance_astm_g173(nm) * std::pow(nm / 550.0, p));
        };
        std::vector<float> s3, s48;
        for (double nm : w3) s3.push_back(spectrum(nm));
        for (double nm : w48) s48.push_back(spectrum(nm));
        const std::array<double, 3> a = SpectrumToRgb(w3, p).convert(s3);
        const std::array<double, 3> b = SpectrumToRgb(w48).convert(s48);
        std::printf("p = %+.0f: three-sample %.4f %.4f %.4f   spectral %.4f %.4f %.4f\n", p, a[0], a[1], a[2],
                    b[0], b[1], b[2]);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c] / b[c], 1.0, 3e-3) << "p " << p << " c " << c;
    }
}

TEST(Color, ThreeSampleMatrixIsDiagonalAndOrderIndependent) {
    const std::vector<double> dec = {680, 550, 440}, inc = {440, 550, 680};
    const SpectrumToRgb a(dec), b(inc);
    const std::vector<float> sd = {1.0f, 2.0f, 3.0f}, si = {3.0f, 2.0f, 1.0f};
    const auto ra = a.convert(sd), rb = b.convert(si);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(ra[c], rb[c]);
    // R depends on the 680 nm sample only, and so on.
    for (int j = 0; j < 3; ++j)
        for (int c = 0; c < 3; ++c)
            if (j != c) {
                EXPECT_EQ(a.matrix()[j * 3 + c], 0.0);
            }
}

TEST(Color, BatchConversionMatchesSingle) {
    const std::vector<double> w = spectral_wavelengths_nm();
    const SpectrumToRgb conv(w);
    std::vector<float> spectra(5 * w.size());
    for (std::size_t k = 0; k < spectra.size(); ++k) spectra[k] = float(std::sin(0.1 * k) + 1.5);
    std::vector<float> rgb(15);
    conv.convert(spectra, rgb);
    for (int i = 0; i < 5; ++i) {
        const auto one = conv.convert(std::span<const float>(spectra).subspan(i * w.size(), w.size()));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb[3 * i + c], one[c], 1e-5 * std::abs(one[c]));
    }
}

TEST(Color, RejectsBadWavelengths) {
    const std::vector<double> two = {500, 600}, unsorted = {440, 680, 550}, repeated = {440, 440, 550, 680};
    EXPECT_THROW(SpectrumToRgb{two}, InvalidArgument);
    EXPECT_THROW(SpectrumToRgb{unsorted}, InvalidArgument);
    EXPECT_THROW(SpectrumToRgb{repeated}, InvalidArgument);
    const SpectrumToRgb ok(default_wavelengths_nm());
    const std::vector<float> wrong(default_wavelengths_nm().size() + 1, 1.0f);
    EXPECT_THROW(ok.convert(wrong), InvalidArgument);
}

TEST(Color, ThreeSampleConversionAgainstPeerSpectralRgb) {
    // tests/data/bruneton2017_sky_subset.csv: the peer's radiance at 680/550/440
    // nm and its RGB from the full 47-sample spectrum (CIE table at 1 nm). Converting the
    // three samples with the approximate method cannot be exact: it assumes the spectrum
    // is the solar one times lambda^-3 around each sample, while the real sky is close to
    // Rayleigh's lambda^-4 away from the sun, much flatter where Mie scattering dominates
    // (towards the sun) and reddened by extinction near the horizon. G and B integrate
    // their colour-matching function near their own sample and barely notice; R is a
    // difference of its positive lobe (560-700 nm) and a negative lobe over 440-540 nm,
    // which the 680 nm sample extrapolated with lambda^-3 gets wrong whenever the true
    // slope differs: for a pure lambda^-4 spectrum R is 4.5 % low, for flatter spectra it
    // is too high. Measured over the 135 rows (sky above and below the horizon):
    //     R: median 5.1 %, worst 21 % (looking at the sun, and at the horizon);
    //        away from the sun (> 30 deg) and above 80 deg zenith: median 3.8 %, worst 7.6 %
    //     G: median 0.9 %, worst 2.1 %;   B: median 1.0 %, worst 3.5 %;
    //     all channels: median 1.8 %, worst 21 %.
    // With the CIE table in place of the Wyman fit the overall median drops from 1.8 % to
    // 1.4 %: the approximation, not the fit, dominates. The bounds asserted below sit just
    // above these measurements, so that a regression of the conversion (a wrong factor,
    // a channel swap, a wrong lambda power) fails. Direct sunlight (p = 0) is checked the
    // same way against Esun_n_R/G/B; there the spectrum is E T, and T reddens it at
    // 60 degrees from the zenith.
    std::vector<std::map<std::string, double>> rows;
    for (const test::PeerRow& row : test::read_peer_table()) rows.push_back(row.v);
    ASSERT_GT(rows.size(), 100u);

    const std::vector<double> w3 = test::kPeerWavelengthsNm;
    const SpectrumToRgb sky(w3, -3.0), sun(w3, 0.0);
    // The same conversion with the CIE table in place of the fit (to split the error).
    std::array<double, 3> k_table{};
    for (int j = 0; j < 3; ++j) {
        const double lj = w3[j];
        for (double nm = 360.0; nm < 830.0; nm += 1.0) {
            const Xyz t = cie_table_at(nm);
            const double cmf =
                kXyzToRgb[3 * j] * t.x + kXyzToRgb[3 * j + 1] * t.y + kXyzToRgb[3 * j + 2] * t.z;
            k_table[j] += cmf * solar_irradiance_astm_g173(nm) / solar_irradiance_astm_g173(lj) *
                          std::pow(nm / lj, -3.0);
        }
    }

    const char* rgb_names[3] = {"L_R", "L_G", "L_B"};
    const char* nm_names[3] = {"L_680nm", "L_550nm", "L_440nm"};
    const char* sun_names[3] = {"Esun_n_R", "Esun_n_G", "Esun_n_B"};
    const char* t_names[3] = {"T_sun_680nm", "T_sun_550nm", "T_sun_440nm"};
    const double E[3] = {1.474, 1.8504, 1.91198};
    std::vector<double> err[3], err_away[3], err_sun[3], all, all_table;
    for (const auto& row : rows) {
        if (!(row.at("L_G") > 0.0)) continue;  // rays that hit the ground at once
        std::vector<float> s, e;
        for (int c = 0; c < 3; ++c) {
            s.push_back(float(row.at(nm_names[c])));
            e.push_back(float(E[c] * row.at(t_names[c])));
        }
        const std::array<double, 3> ours = sky.convert(s), sun_rgb = sun.convert(e);
        const bool away = row.at("scatter_angle_deg") >= 30.0 && row.at("view_zenith_deg") <= 80.0;
        for (int c = 0; c < 3; ++c) {
            const double peer = row.at(rgb_names[c]);
            const double rel = std::abs(ours[c] - peer) / peer;
            err[c].push_back(rel);
            all.push_back(rel);
            all_table.push_back(std::abs(k_table[c] * s[c] - peer) / peer);
            if (away) err_away[c].push_back(rel);
            err_sun[c].push_back(std::abs(sun_rgb[c] - row.at(sun_names[c])) / row.at(sun_names[c]));
        }
    }
    auto worst = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
    std::printf(
        "three-sample sky RGB vs peer, %zu values: median %.2f %%, worst %.2f %% "
        "(with the CIE table: median %.2f %%, worst %.2f %%)\n",
        all.size(), 100 * median(all), 100 * worst(all), 100 * median(all_table), 100 * worst(all_table));
    const char* ch = "RGB";
    for (int c = 0; c < 3; ++c)
        std::printf(
            "  %c: sky median %.2f %% worst %.2f %% | away from sun and horizon "
            "median %.2f %% worst %.2f %% | direct sun median %.2f %% worst %.2f %%\n",
            ch[c], 100 * median(err[c]), 100 * worst(err[c]), 100 * median(err_away[c]),
            100 * worst(err_away[c]), 100 * median(err_sun[c]), 100 * worst(err_sun[c]));
    // Bounds: the measurements above, rounded up.
    EXPECT_LT(median(err[0]), 0.06);
    EXPECT_LT(worst(err[0]), 0.23);
    EXPECT_LT(worst(err_away[0]), 0.09);
    for (int c = 1; c < 3; ++c) {
        EXPECT_LT(median(err[c]), 0.012) << ch[c];
        EXPECT_LT(worst(err[c]), 0.04) << ch[c];
    }
    // Direct sun, measured: R median 4.3 % worst 7.5 %, G 0.24 % / 0.45 %, B 1.0 % / 1.75 %
    // (the approximation assumes E T has the solar spectrum's shape; T is bluer-poor).
    const double sun_median[3] = {0.05, 0.004, 0.012}, sun_worst[3] = {0.08, 0.006, 0.02};
    for (int c = 0; c < 3; ++c) {
        EXPECT_LT(median(err_sun[c]), sun_median[c]) << ch[c];
        EXPECT_LT(worst(err_sun[c]), sun_worst[c]) << ch[c];
    }
}
