// SPDX-License-Identifier: Apache-2.0
// The night sky's own light (night/night_glow.hpp): the zodiacal light against Leinert et
// al. 1998's Table 16 and along the moment's ecliptic, the airglow's brightening against
// van Rhijn's closed form and its lines' energy on any wavelength grid, and the image's
// invariants for every preset.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>

#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"
#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/math.hpp"
#include "welkin/night/night_glow.hpp"

namespace welkin {
namespace {

using test::parameter_of;

// A frame that puts the zenith at helioecliptic longitude 90 degrees and ecliptic
// latitude beta (the sun at longitude 0): a proper rotation taking enu z to
// (0, cos beta, sin beta) and enu x to the ecliptic's x.
EclipticFrame zenith_at(double beta_deg) {
    const double b = beta_deg * kDegree;
    EclipticFrame f;
    // Columns: images of enu x, y, z.
    f.enu_to_ecliptic = {
        {{1.0, 0.0, 0.0}, {0.0, std::sin(b), std::cos(b)}, {0.0, -std::cos(b), std::sin(b)}}};
    f.sun_longitude_deg = 0.0;
    return f;
}

// Mean of channel c over the image's row j.
double row_mean(const std::vector<float>& px, int width, std::size_t nc, int j, std::size_t c) {
    double s = 0.0;
    for (int i = 0; i < width; ++i) s += px[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * nc + c];
    return s / width;
}

TEST(NightGlow, ZodiacalLightIsLeinertsTable) {
    // The table's nodes, and its folding: |lambda - lambda_sun|, |beta|.
    EXPECT_DOUBLE_EQ(zodiacal_light_s10(90.0, 0.0), 202.0);
    EXPECT_DOUBLE_EQ(zodiacal_light_s10(-90.0, -60.0), 67.0);
    EXPECT_DOUBLE_EQ(zodiacal_light_s10(270.0, 60.0), 67.0);
    EXPECT_DOUBLE_EQ(zodiacal_light_s10(180.0, 0.0), 180.0);  // the gegenschein
    EXPECT_DOUBLE_EQ(zodiacal_light_s10(123.0, 90.0), 60.0);  // the pole
    // Halfway between nodes: the mean of the four around.
    EXPECT_DOUBLE_EQ(zodiacal_light_s10(52.5, 37.5), 0.25 * (195.0 + 130.0 + 143.0 + 105.0));
    EXPECT_EQ(parameter_of([] { zodiacal_light_s10(NAN, 0.0); }), "helioecliptic_longitude_deg");
    EXPECT_EQ(parameter_of([] { zodiacal_light_s10(0.0, INFINITY); }), "ecliptic_latitude_deg");
}

TEST(NightGlow, EclipticFrameAgainstTheSunAndTheEquinox) {
    // The March equinox of 2026 is 20 March 14:46 UTC (USNO's "Earth's Seasons" table: the
    // sun's geocentric apparent longitude 0). The frame is the mean ecliptic and equinox of
    // date (nutation in longitude, at most 17.2", left out) and topocentric (the solar
    // parallax, 8.8"): the sun's longitude then is within 26", 0.0072 degrees, of 0, where
    // it moves 0.00068 degrees a minute.
    const Place greenwich{51.4779, 0.0, 46.0};
    const auto lon_at = [&](const char* t) {
        const double l = ecliptic_frame(Instant::from_civil(parse_iso8601(t)), greenwich).sun_longitude_deg;
        return l > 180.0 ? l - 360.0 : l;
    };
    EXPECT_NEAR(lon_at("2026-03-20T14:46:00Z"), 0.0, 0.0072);
    EXPECT_NEAR(lon_at("2026-03-20T15:46:00Z") - lon_at("2026-03-20T14:46:00Z"), 0.0411, 0.002);
    // The sun's own direction (high in the sky: refraction under 1') lands on the
    // ecliptic at the sun's longitude, and the frame is a rotation.
    const Instant when = Instant::from_civil(parse_iso8601("2026-06-21T12:00:00Z"));
    const EclipticFrame f = ecliptic_frame(when, greenwich);
    const auto& d = sun_and_moon(when, greenwich).sun.direction_enu;
    const auto& m = f.enu_to_ecliptic;
    double e[3];
    for (int i = 0; i < 3; ++i)
        e[i] = m[std::size_t(i)][0] * d[0] + m[std::size_t(i)][1] * d[1] + m[std::size_t(i)][2] * d[2];
    EXPECT_NEAR(std::asin(e[2]) / kDegree, 0.0, 0.02);
    EXPECT_NEAR(std::atan2(e[1], e[0]) / kDegree, f.sun_longitude_deg, 0.02);
    EXPECT_NEAR(f.sun_longitude_deg, 90.0, 0.2);  // the June solstice is 21 June 08:24 UTC
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double dot = 0.0;
            for (int k = 0; k < 3; ++k)
                dot += m[std::size_t(i)][std::size_t(k)] * m[std::size_t(j)][std::size_t(k)];
            EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-12);
        }
}

TEST(NightGlow, ZodiacalLightOnTheEclipticOverHighLatitudeIsTheTablesRatio) {
    // The same elongation (90 degrees: helioecliptic longitude 90 at any latitude), at the
    // zenith (the same air), on the ecliptic and 60 degrees off it: 202 / 67 S10.
    const Atmosphere atm = Atmosphere::preset("clear_day");
    const Observer o = Observer{0.0, {0.0, 0.0, 1.0}}.validated();
    const int width = 512;
    NightGlowOptions zodi;
    zodi.airglow = false;
    zodi.ecliptic = zenith_at(0.0);
    const auto on =
        night_glow_pixels(atm, o, width, SkyImageOptions::Output::Spectral, ColorSpace::Rec709, zodi);
    zodi.ecliptic = zenith_at(60.0);
    const auto off =
        night_glow_pixels(atm, o, width, SkyImageOptions::Output::Spectral, ColorSpace::Rec709, zodi);
    for (std::size_t c = 0; c < atm.channels(); ++c) {
        const double ratio =
            row_mean(on, width, atm.channels(), 0, c) / row_mean(off, width, atm.channels(), 0, c);
        EXPECT_NEAR(ratio, 202.0 / 67.0, 0.01 * 202.0 / 67.0) << "channel " << c;
    }
    // The zenith on the ecliptic at 90 degrees from the sun: 202 S10 through the air, at
    // 500 nm the sun's shape scaled to S10's V radiance (545 nm) -> at 545 nm within the
    // reddening's few per cent.
    const double t = transmittance_to_boundary(atm, atm.bottom_radius_m, 1.0)[1];  // 560 nm
    const double expected_560 =
        202.0 * v_surface_brightness_to_radiance(27.78151250383644) * atm.solar_irradiance[1] /
        (atm.solar_irradiance[1] +
         (atm.solar_irradiance[2] - atm.solar_irradiance[1]) * (545.0 - 560.0) / (480.0 - 560.0));
    EXPECT_NEAR(row_mean(on, width, atm.channels(), 0, 1) / (expected_560 * t), 1.0, 0.1);
}

TEST(NightGlow, ZodiacalLightFollowsTheEveningAndMorningEcliptic) {
    // La Palma, new moon of March 2026: after dusk the zodiacal light stands in the west,
    // before dawn in the east, its brightest above the horizon towards the sun's azimuth.
    const Place place{28.7606, -17.8816, 2396.0};
    const Atmosphere atm = Atmosphere::preset("clear_day");
    const Observer o = Observer{0.0, {0.0, 0.0, 1.0}}.validated();
    const int width = 256, height = width / 2;
    NightGlowOptions zodi;
    zodi.airglow = false;
    for (const char* when_text : {"2026-03-19T20:45:00Z", "2026-03-20T06:00:00Z"}) {
        const Instant when = Instant::from_civil(parse_iso8601(when_text));
        const SunAndMoon sm = sun_and_moon(when, place);
        ASSERT_LT(sm.sun.elevation_deg, -15.0) << when_text;
        zodi.ecliptic = ecliptic_frame(when, place);
        const auto px =
            night_glow_pixels(atm, o, width, SkyImageOptions::Output::Spectral, ColorSpace::Rec709, zodi);
        double west = 0.0, east = 0.0, best = -1.0, best_azimuth = 0.0;
        for (int j = 0; j < height / 2; ++j)
            for (int i = 0; i < width; ++i) {
                const glm::dvec3 d = equirect_pixel_direction(i, j, width, height);
                const double e = std::asin(d.z) / kDegree;
                if (e < 15.0 || e > 40.0) continue;
                const double v =
                    px[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * atm.channels() + 1];
                (d.x < 0.0 ? west : east) += v;
                if (v > best) {
                    best = v;
                    best_azimuth = std::atan2(d.x, d.y) / kDegree;
                }
            }
        const bool evening = sm.sun.azimuth_deg > 180.0;
        EXPECT_GT(evening ? west / east : east / west, 1.3) << when_text;
        double gap = std::fmod(std::abs(best_azimuth - sm.sun.azimuth_deg), 360.0);
        gap = std::min(gap, 360.0 - gap);
        EXPECT_LT(gap, 40.0) << when_text << " brightest at azimuth " << best_azimuth << ", sun at "
                             << sm.sun.azimuth_deg;
    }
}

TEST(NightGlow, AirglowBrightensAsVanRhijnsClosedForm) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const std::size_t nc = atm.channels();
    for (double altitude : {0.0, 3000.0}) {
        const Observer o = Observer{altitude, {0.0, 0.0, 1.0}}.validated();
        NightGlowOptions air;
        air.zodiacal_light = false;
        const int width = 512, height = width / 2;
        const auto px =
            night_glow_pixels(atm, o, width, SkyImageOptions::Output::Spectral, ColorSpace::Rec709, air);
        const std::vector<double> zenith = airglow_zenith_radiance(atm.wavelengths_nm);
        const double q = (atm.bottom_radius_m + altitude) / (atm.bottom_radius_m + kAirglowHeight_m);
        for (int j = 0; j < height / 2; ++j) {
            const double sin_e = equirect_pixel_direction(0, j, width, height).z;
            if (sin_e < std::sin(2.0 * kDegree)) continue;
            const double closed_form = 1.0 / std::sqrt(1.0 - q * q * (1.0 - sin_e * sin_e));
            const std::vector<double> t =
                transmittance_to_boundary(atm, atm.bottom_radius_m + altitude, sin_e);
            for (std::size_t c = 0; c < nc; ++c)
                EXPECT_NEAR(row_mean(px, width, nc, j, c) / (zenith[c] * t[c] * closed_form), 1.0, 2e-3)
                    << "row " << j << " channel " << c;
        }
        // The closed form itself: 1 at the zenith, 1 / sqrt(1 - q^2) at the horizon.
        EXPECT_DOUBLE_EQ(van_rhijn_factor(1.0, 1.0, 2.0), 1.0);
        EXPECT_DOUBLE_EQ(van_rhijn_factor(0.0, 1.0, 2.0), 1.0 / std::sqrt(0.75));
    }
}

TEST(NightGlow, AirglowLinesKeepTheirEnergyOnAnyGrid) {
    // The integral of the channels' linear interpolant is the lines' radiance (1 R =
    // 1e10 / 4 pi photons s^-1 m^-2 sr^-1, h c / lambda each) plus the continuum's own
    // trapezoid integral, exactly, on any grid, increasing or decreasing; a line beyond the
    // end channels lands whole on the nearer one.
    const auto photons_to_w = [](double lambda_nm) {
        return 1e10 / (4.0 * kPi) * 6.62607015e-34 * 299792458.0 / (lambda_nm * 1e-9);
    };
    const auto check = [&](const std::vector<double>& wl) {
        const std::vector<double> l = airglow_zenith_radiance(wl);
        double got = 0.0, continuum = 0.0;
        for (std::size_t k = 0; k + 1 < wl.size(); ++k) {
            const double h = std::abs(wl[k + 1] - wl[k]);
            got += 0.5 * (l[k] + l[k + 1]) * h;
            continuum +=
                0.5 * kAirglowContinuumRayleighPerNm * (photons_to_w(wl[k]) + photons_to_w(wl[k + 1])) * h;
        }
        double lines = 0.0;
        for (const AirglowLine& line : airglow_lines()) lines += line.rayleigh * photons_to_w(line.lambda_nm);
        EXPECT_NEAR((got - continuum) / lines, 1.0, 1e-9)
            << wl.front() << "-" << wl.back() << ", " << wl.size();
    };
    check(spectral_wavelengths_nm(10.0));
    check(spectral_wavelengths_nm(5.0));
    std::vector<double> uneven{360.0, 401.0, 450.0, 555.0, 557.7, 560.0, 600.0, 633.0, 700.0, 830.0};
    check(uneven);
    std::reverse(uneven.begin(), uneven.end());
    check(uneven);
    check(default_wavelengths_nm());  // 620 ... 440: the O I red lines beyond 620
}

TEST(NightGlow, FiniteNonNegativeAndDarkBelowTheHorizonForEveryPreset) {
    const Instant when = Instant::from_civil(parse_iso8601("2026-03-19T00:30:00Z"));
    const EclipticFrame frame = ecliptic_frame(when, Place{28.7606, -17.8816, 2396.0});
    for (const std::string& name : Atmosphere::preset_names()) {
        const Atmosphere atm = Atmosphere::preset(name);
        const Observer o = Observer{0.0, {0.0, 0.0, 1.0}}.validated();
        for (const auto output : {SkyImageOptions::Output::Rgb, SkyImageOptions::Output::Spectral}) {
            for (const bool with_moment : {false, true}) {
                NightGlowOptions glow;
                if (with_moment) glow.ecliptic = frame;
                const int width = 64, height = 32;
                const auto px = night_glow_pixels(atm, o, width, output, ColorSpace::Rec709, glow);
                const std::size_t nc = output == SkyImageOptions::Output::Rgb ? 3 : atm.channels();
                ASSERT_EQ(px.size(), std::size_t(width) * std::size_t(height) * nc);
                for (int j = 0; j < height; ++j) {
                    const double sin_e = equirect_pixel_direction(0, j, width, height).z;
                    double row_sum = 0.0;
                    for (std::size_t k = 0; k < std::size_t(width) * nc; ++k) {
                        const float v = px[std::size_t(j) * std::size_t(width) * nc + k];
                        ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << name << " row " << j;
                        row_sum += v;
                    }
                    if (sin_e < 0.0) {
                        EXPECT_EQ(row_sum, 0.0) << name << " row " << j;
                    } else if (sin_e > 0.2) {
                        EXPECT_GT(row_sum, 0.0) << name << " row " << j;
                    }
                }
            }
        }
    }
}

TEST(NightGlow, BadInput) {
    const Atmosphere atm = Atmosphere::preset("clear_day");
    EXPECT_EQ(parameter_of([&] { night_glow_pixels(atm, Observer{}, 15, SkyImageOptions::Output::Rgb); }),
              "width");
    EXPECT_EQ(parameter_of([] { airglow_zenith_radiance(std::vector<double>{}); }), "wavelengths_nm");
    EXPECT_EQ(
        parameter_of([] {
            ecliptic_frame(Instant::from_civil(parse_iso8601("2026-01-01T00:00:00Z")), Place{95.0, 0.0, 0.0});
        }),
        "latitude_deg");
}

}  // namespace
}  // namespace welkin
