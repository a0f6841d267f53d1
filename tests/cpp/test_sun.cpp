// SPDX-License-Identifier: Apache-2.0
// The sun: limb darkening (normalisation, Neckel & Labs' own mean/centre ratios), the
// visible fraction at the horizon, transmittance against the peer.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/atmosphere/sun.hpp"
#include "welkin/atmosphere/sun_disc.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"

using namespace welkin;

namespace {

// Integral of a limb-darkening profile over the disc's solid angle, 2 pi int sin(rho)
// LD(rho) drho, by the midpoint rule on 200000 intervals (LD has a square-root edge at
// the limb: the error is ~ h^1.5, < 1e-7 relative here).
double disc_integral(const LimbDarkening& ld, double alpha) {
    const int n = 200000;
    const double h = alpha / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double rho = (i + 0.5) * h;
        sum += std::sin(rho) * ld(rho);
    }
    return kTwoPi * sum * h;
}

Observer sun_at(double elevation_rad, double altitude_m = 0.0) {
    Observer o;
    o.altitude_m = altitude_m;
    o.sun_direction = {std::cos(elevation_rad), 0.0, std::sin(elevation_rad)};
    return o;
}

}  // namespace

TEST(Sun, LimbDarkeningIntegratesToTheDiscSolidAngle) {
    for (double alpha : {0.004675, 0.05, 0.2}) {
        const double omega = kTwoPi * (1.0 - std::cos(alpha));
        for (double nm : {300.0, 360.0, 440.0, 550.0, 680.0, 830.0, 1100.0, 2000.0}) {
            const LimbDarkening ld(alpha, nm);
            EXPECT_NEAR(disc_integral(ld, alpha) / omega, 1.0, 1e-6) << alpha << " " << nm;
        }
    }
}

TEST(Sun, LimbDarkeningMatchesNeckelLabsMeanToCentreRatios) {
    // Neckel & Labs 1994's own column: mean disc intensity over central intensity, given
    // to 4 decimals beside each row of coefficients. Our centre value is the inverse.
    const std::pair<double, double> rows[] = {
        {303.327, 0.6826}, {349.947, 0.7260}, {365.875, 0.7445}, {401.970, 0.7303}, {445.125, 0.7596},
        {541.760, 0.8002}, {610.975, 0.8221}, {669.400, 0.8360}, {811.760, 0.8621}, {1098.95, 0.8890}};
    for (const auto& [nm, ratio] : rows) {
        const LimbDarkening ld(0.004675, nm);
        EXPECT_NEAR(1.0 / ld.centre(), ratio, 1.2e-4) << nm;
        EXPECT_NEAR(ld(0.0), ld.centre(), 1e-12);
    }
}

TEST(Sun, LimbDarkeningShape) {
    const double alpha = 0.004675;
    for (double nm : {440.0, 550.0, 680.0}) {
        double last = limb_darkening(0.0, alpha, nm);
        for (int k = 1; k <= 100; ++k) {
            const double v = limb_darkening(alpha * k / 100.0, alpha, nm);
            EXPECT_LE(v, last + 1e-12) << nm << " " << k;  // darker towards the limb
            last = v;
        }
        EXPECT_EQ(limb_darkening(alpha * 1.0001, alpha, nm), 0.0);
        EXPECT_EQ(limb_darkening(-1e-9, alpha, nm), 0.0);
    }
    // Bluer light darkens more: limb / centre is a0 (0.153 at 445 nm, 0.347 at 669 nm).
    const double blue = limb_darkening(alpha, alpha, 445.125) / limb_darkening(0, alpha, 445.125);
    const double red = limb_darkening(alpha, alpha, 669.4) / limb_darkening(0, alpha, 669.4);
    EXPECT_NEAR(blue, 0.15248, 1e-4);
    EXPECT_NEAR(red, 0.34685, 1e-4);
}

TEST(Sun, VisibleFractionIsTheCircularSegmentAboveTheHorizon) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const double a = atm.sun_angular_radius_rad;
    auto frac = [&](double e, double alt = 0.0) {
        return sun_radiometry(atm, sun_at(e, alt)).visible_fraction;
    };
    EXPECT_DOUBLE_EQ(frac(0.5), 1.0);
    EXPECT_NEAR(frac(a * (1 + 1e-9)), 1.0, 1e-9);
    EXPECT_NEAR(frac(0.0), 0.5, 1e-12);
    EXPECT_NEAR(frac(-a * (1 + 1e-9)), 0.0, 1e-9);
    // Chord at half the radius: 1 - (acos(1/2) - sqrt(3)/4) / pi = 0.80450.
    EXPECT_NEAR(frac(0.5 * a), 1.0 - (std::acos(0.5) - std::sqrt(3.0) / 4.0) / kPi, 1e-9);
    EXPECT_NEAR(frac(-0.5 * a), (std::acos(0.5) - std::sqrt(3.0) / 4.0) / kPi, 1e-9);
    // From 10 km up the horizon dips by acos(R / (R + h)).
    const double dip = std::acos(atm.bottom_radius_m / (atm.bottom_radius_m + 10e3));
    EXPECT_NEAR(frac(-dip, 10e3), 0.5, 1e-6);
    EXPECT_NEAR(frac(-dip + a * 1.001, 10e3), 1.0, 1e-9);
}

TEST(Sun, DirectIrradianceIsSolarTimesTransmittanceTimesFraction) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const double r = atm.bottom_radius_m;
    for (double e_deg : {90.0, 30.0, 5.0}) {
        const SunRadiometry s = sun_radiometry(atm, sun_at(e_deg * kDegree));
        const std::vector<double> t = transmittance_to_boundary(atm, r, std::sin(e_deg * kDegree));
        ASSERT_EQ(s.transmittance.size(), 3u);
        for (int c = 0; c < 3; ++c) {
            EXPECT_DOUBLE_EQ(s.transmittance[c], t[c]);
            EXPECT_DOUBLE_EQ(s.direct_irradiance[c], atm.solar_irradiance[c] * t[c]);
        }
    }
    // Horizon cutting the disc: the fraction multiplies, T stays finite and positive.
    const SunRadiometry h = sun_radiometry(atm, sun_at(0.0));
    for (int c = 0; c < 3; ++c) {
        EXPECT_GT(h.transmittance[c], 0.0);
        EXPECT_DOUBLE_EQ(h.direct_irradiance[c],
                         atm.solar_irradiance[c] * h.transmittance[c] * h.visible_fraction);
    }
}

TEST(Sun, TransmittanceIsContinuousWhereTheHorizonStartsToCutTheDisc) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const double a = atm.sun_angular_radius_rad;
    const SunRadiometry above = sun_radiometry(atm, sun_at(a * (1 + 1e-7)));
    const SunRadiometry below = sun_radiometry(atm, sun_at(a * (1 - 1e-7)));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(above.transmittance[c] / below.transmittance[c], 1.0, 1e-4) << c;
}

TEST(Sun, BelowTheHorizonAndFromSpace) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const SunRadiometry night = sun_radiometry(atm, sun_at(-0.2));
    EXPECT_EQ(night.visible_fraction, 0.0);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(night.transmittance[c], 0.0);
        EXPECT_EQ(night.direct_irradiance[c], 0.0);
    }
    // 1000 km up, sun overhead: the ray to the sun never enters the atmosphere.
    const SunRadiometry space = sun_radiometry(atm, sun_at(0.5 * kPi, 1e6));
    for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(space.transmittance[c], 1.0);
        EXPECT_DOUBLE_EQ(space.direct_irradiance[c], atm.solar_irradiance[c]);
    }
    // Sun straight down from space: behind the planet.
    EXPECT_EQ(sun_radiometry(atm, sun_at(-0.5 * kPi, 1e6)).visible_fraction, 0.0);
    // Bad input names the parameter.
    Observer bad = sun_at(0.3);
    bad.altitude_m = -1.0;
    EXPECT_THROW(sun_radiometry(atm, bad), InvalidArgument);
}

TEST(Sun, TransmittanceAgreesWithThePeer) {
    // tests/data: T_sun at the ground for sun zenith 0, 30, 60 degrees (the
    // peer's transmittance texture); ours is exact quadrature. Measured: worst 0.001 %.
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    int checked = 0;
    double worst = 0.0;
    for (const test::PeerRow& row : test::read_peer_table()) {
        auto col = [&](const std::string& name) { return row[name]; };
        const double zenith = col("sun_zenith_deg") * kDegree;
        const SunRadiometry s = sun_radiometry(atm, sun_at(0.5 * kPi - zenith));
        const double peer[3] = {col("T_sun_680nm"), col("T_sun_550nm"), col("T_sun_440nm")};
        for (int c = 0; c < 3; ++c) {
            const double rel = std::abs(s.transmittance[c] / peer[c] - 1.0);
            worst = std::max(worst, rel);
            EXPECT_LT(rel, 3e-3) << "sun zenith " << col("sun_zenith_deg") << " channel " << c;
        }
        ++checked;
    }
    std::printf("sun transmittance vs peer over %d rows: worst %.4f %%\n", checked, 100 * worst);
    EXPECT_GT(checked, 100);
}

// The disc model (sun_disc.hpp): its radiance integrated over the visible disc is the
// direct irradiance, and the RGB polynomial form is the RGB of the spectral disc.
TEST(SunDisc, IntegralOverTheDiscIsTheDirectIrradiance) {
    for (const char* preset : {"clear", "hazy"}) {
        const Atmosphere atm = Atmosphere::preset(preset, {440.0, 550.0, 680.0});
        for (double elev_deg : {60.0, 5.0}) {
            const SunDisc disc(atm, sun_at(elev_deg * kPi / 180.0));
            const double alpha = disc.angular_radius_rad();
            for (std::size_t c = 0; c < atm.channels(); ++c) {
                const int n = 100000;
                const double h = alpha / n;
                double sum = 0.0;
                for (int i = 0; i < n; ++i) {
                    const double rho = (i + 0.5) * h;
                    sum += std::sin(rho) * disc.radiance(c, rho);
                }
                const double e = disc.radiometry().direct_irradiance[c];
                EXPECT_NEAR(kTwoPi * sum * h, e, 1e-6 * e) << preset << " " << elev_deg << " " << c;
            }
            EXPECT_EQ(disc.radiance(0, alpha * 1.001), 0.0);
        }
    }
}

// The RGB disc (sun_disc.hpp): each channel's limb profile is a convex combination of the
// per-wavelength Neckel & Labs profiles (positive, 1 at the centre, darkening to the limb),
// its integral over the disc is the lamp's gamut-mapped colour, and where the conversion's
// negative lobes carry little light it follows the RGB of the spectral disc closely.
TEST(SunDisc, RgbPolynomialIsAPhysicalProfileWithTheLampsEnergy) {
    for (const char* preset : {"clear_day", "polluted", "desert_dust"})
        for (double elevation : {0.5, 0.05, 0.01}) {
            const Atmosphere atm = Atmosphere::preset(preset, spectral_wavelengths_nm(40.0));
            const SunDisc disc(atm, sun_at(elevation));
            const SpectrumToRgb to_rgb(atm.wavelengths_nm, 0.0);
            const SunDisc::Rgb rgb = disc.rgb(to_rgb.matrix(), to_rgb.luminance_weights());
            const double alpha = disc.angular_radius_rad();
            std::vector<float> e(atm.channels());
            for (std::size_t c = 0; c < atm.channels(); ++c)
                e[c] = float(disc.radiometry().direct_irradiance[c]);
            const std::array<double, 3> lamp = to_rgb.convert(e);
            for (int j = 0; j < 3; ++j) {
                ASSERT_GE(rgb.centre_radiance[j], 0.0) << preset << " " << elevation;
                double integral = 0.0, last = 2.0;
                const int n = 4000;
                for (int q = 0; q < n; ++q) {
                    const double rho = (q + 0.5) * alpha / n;
                    const double s = std::sin(rho) / std::sin(alpha), mu = std::sqrt(1.0 - s * s);
                    double p = 0.0;
                    for (int k = 5; k >= 0; --k) p = p * mu + rgb.limb_coefficients[j][k];
                    EXPECT_GT(p, 0.0);
                    EXPECT_LT(p, last);  // darkening outwards
                    last = p;
                    integral += kTwoPi * std::sin(rho) * rgb.centre_radiance[j] * p * alpha / n;
                }
                EXPECT_NEAR(integral, lamp[j], 2e-4 * (lamp[0] + lamp[1] + lamp[2])) << preset << " " << j;
            }
            // Against the per-pixel RGB of the spectral disc, half-way out.
            std::vector<float> spectrum(atm.channels());
            for (std::size_t c = 0; c < atm.channels(); ++c)
                spectrum[c] = float(disc.radiance(c, 0.5 * alpha));
            const std::array<double, 3> want = to_rgb.convert(spectrum);
            const double mu = std::sqrt(0.75);
            for (int j = 0; j < 3; ++j) {
                double p = 0.0;
                for (int k = 5; k >= 0; --k) p = p * mu + rgb.limb_coefficients[j][k];
                EXPECT_NEAR(rgb.centre_radiance[j] * p, want[j], 0.02 * (want[0] + want[1] + want[2]))
                    << preset << " " << elevation << " " << j;
            }
        }
}
