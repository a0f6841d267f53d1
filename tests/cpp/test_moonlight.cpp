// SPDX-License-Identifier: Apache-2.0
// The moon as a light source (astro/moonlight.hpp, night/moonlit_sky.hpp): its
// illuminance on the ground against Krisciunas & Schaefer 1991, its disc's energy in the
// sky image against its irradiance at any resolution, the phase's shape, and the moonlit
// sky's linearity, in one pass with the sun's, and the disc as a formula for hosts.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>

#include "welkin/astro/moonlight.hpp"
#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/sun.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"
#include "welkin/night/moonlit_sky.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/sky/method.hpp"

namespace welkin {
namespace {

constexpr double kMeanMoon_m = 384400e3, kAu_m = 149597870.7e3;

glm::dvec3 from_elevation_azimuth(double e_deg, double a_deg) {
    const double e = e_deg * kDegree, a = a_deg * kDegree;
    return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

// The sun's direction from the moon for a phase angle: rotate the direction from the moon
// back to the observer (-m) by alpha about an axis perpendicular to it.
glm::dvec3 sun_from_moon(const glm::dvec3& m, double alpha_deg) {
    const glm::dvec3 back = -glm::normalize(m);
    glm::dvec3 axis = glm::normalize(glm::cross(back, glm::dvec3(0.0, 0.0, 1.0)));
    const double a = alpha_deg * kDegree;
    // Rodrigues' rotation of `back` about `axis` (perpendicular to it).
    return back * std::cos(a) + glm::cross(axis, back) * std::sin(a);
}

// Krisciunas & Schaefer 1991 (PASP 103, 1033): the moon's illuminance outside the
// atmosphere, eq. 8, I* = 10^(-0.4 (3.84 + 0.026 |alpha| + 4e-9 alpha^4)) foot-candles,
// dimmed by 10^(-0.4 k X(Z)) with X(Z) = (1 - 0.96 sin^2 Z)^(-1/2) (eq. 3) and their
// V-band extinction k = 0.172 mag per air mass (Mauna Kea). The bound: 20 %.
// Welkin's side is independent of K&S's extinction and units: the sky preset's own solar
// spectrum through CIE 1931 y-bar (683 lm/W) and its transmittance towards the moon; the
// brightness law (Allen's V(alpha)) is the one both use.
TEST(Moonlight, GroundIlluminanceMatchesKrisciunasSchaefer) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", spectral_wavelengths_nm(10.0));
    for (double alpha : {0.0, 30.0, 60.0, 90.0, 120.0}) {
        const double ratio = moon_irradiance_ratio(alpha, kMeanMoon_m, kAu_m);
        for (double elevation : {20.0, 45.0, 70.0, 90.0}) {
            Observer o;
            o.sun_direction = from_elevation_azimuth(elevation, 0.0);
            const SunRadiometry air = sun_radiometry(atm, o.validated());
            double lux = 0.0;
            for (std::size_t c = 0; c < atm.channels(); ++c)
                lux += 683.0 * atm.solar_irradiance[c] * ratio * air.transmittance[c] *
                       cie1931_cmf(atm.wavelengths_nm[c]).y * 10.0;
            const double z = (90.0 - elevation) * kDegree;
            const double airmass = 1.0 / std::sqrt(1.0 - 0.96 * std::sin(z) * std::sin(z));
            const double ks_lux = 10.764 *
                                  std::pow(10.0, -0.4 * (3.84 + 0.026 * alpha + 4e-9 * std::pow(alpha, 4))) *
                                  std::pow(10.0, -0.4 * 0.172 * airmass);
            EXPECT_NEAR(lux / ks_lux, 1.0, 0.2) << "phase " << alpha << " elevation " << elevation;
        }
    }
    // The full moon at the zenith outside the air: about 0.3 lux (Allen: V = -12.73).
    EXPECT_NEAR(10.764 * std::pow(10.0, -0.4 * 3.84), 0.313, 0.001);
}

// The disc's integral over the image, sum radiance x pixel solid angle, is the moon's
// irradiance through the air, E_sun ratio T, per wavelength, at every resolution, for any
// phase; and the lit part lies towards the sun.
TEST(Moonlight, DiscEnergyIsTheIrradianceAtAnyResolution) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    Observer o;
    Moon moon;
    moon.direction = from_elevation_azimuth(40.0, 20.0);
    moon.angular_radius_rad = 0.259 * kDegree;
    for (double alpha : {0.0, 60.0, 90.0, 150.0}) {
        moon.sun_from_moon = sun_from_moon(moon.direction, alpha);
        moon.irradiance_ratio = moon_irradiance_ratio(alpha, kMeanMoon_m, kAu_m);
        Observer mo = o;
        mo.sun_direction = moon.direction;
        Atmosphere moon_atm = atm;
        moon_atm.sun_angular_radius_rad = moon.angular_radius_rad;
        const SunRadiometry air = sun_radiometry(moon_atm, mo.validated());
        for (int width : {16, 256, 2048}) {
            const int height = width / 2;
            const std::vector<float> px =
                moon_disc_pixels(atm, o, moon, width, SkyImageOptions::Output::Spectral);
            const std::size_t nc = atm.channels();
            std::vector<double> energy(nc, 0.0);
            glm::dvec3 centroid{0.0};
            for (int j = 0; j < height; ++j)
                for (int i = 0; i < width; ++i)
                    for (std::size_t c = 0; c < nc; ++c) {
                        const double v = px[(std::size_t(j) * width + i) * nc + c];
                        ASSERT_TRUE(std::isfinite(v) && v >= 0.0);
                        energy[c] += v * equirect_pixel_solid_angle(j, width, height);
                        if (c == 0) centroid += v * equirect_pixel_direction(i, j, width, height);
                    }
            for (std::size_t c = 0; c < nc; ++c) {
                const double expected =
                    atm.solar_irradiance[c] * moon.irradiance_ratio * air.transmittance[c];
                EXPECT_NEAR(energy[c] / expected, 1.0, 1e-5) << "width " << width << " phase " << alpha;
            }
            // At a crescent or a quarter, the light's centroid leans towards the sun's side
            // (in a 2048-px image, where the disc spans several pixels).
            if (width == 2048 && alpha >= 60.0) {
                const glm::dvec3 m = glm::normalize(moon.direction);
                const glm::dvec3 towards_sun =
                    glm::normalize(moon.sun_from_moon - glm::dot(moon.sun_from_moon, m) * m);
                const glm::dvec3 c = glm::normalize(centroid);
                EXPECT_GT(glm::dot(c - glm::dot(c, m) * m, towards_sun), 0.0) << "phase " << alpha;
            }
        }
    }
}

// The lit fraction of the disc's area is (1 + cos alpha) / 2 (Meeus eq. 48.1): the
// terminator of moon_disc_relative_radiance is where it must be.
TEST(Moonlight, LitAreaIsTheIlluminatedFraction) {
    const std::array<double, 3> m{0.0, 0.0, 1.0};
    const double radius = 0.259 * kDegree;
    for (double alpha : {10.0, 45.0, 90.0, 135.0, 170.0}) {
        const double a = alpha * kDegree;
        const std::array<double, 3> s{std::sin(a), 0.0, -std::cos(a)};  // from the moon, alpha from -m
        int lit = 0, inside = 0;
        const int n = 400;
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const double px = (2.0 * (x + 0.5) / n - 1.0) * radius,
                             py = (2.0 * (y + 0.5) / n - 1.0) * radius;
                if (px * px + py * py >= radius * radius) continue;
                ++inside;
                const double nrm = std::sqrt(1.0 + px * px + py * py);
                if (moon_disc_relative_radiance({px / nrm, py / nrm, 1.0 / nrm}, m, radius, s) > 0.0) ++lit;
            }
        EXPECT_NEAR(double(lit) / inside, 0.5 * (1.0 + std::cos(a)), 0.01) << "phase " << alpha;
    }
}

// The moonlit sky is the sun's sky for a "sun" at the moon, scaled by the ratio: with the
// sun far below the horizon (no sunlight in the sky at all), the image without the disc
// is exactly that scaled image.
TEST(Moonlight, MoonlitSkyIsTheScaledSky) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const auto method = make_sky_method("lut");
    Observer o;
    o.sun_direction = from_elevation_azimuth(-60.0, 0.0);
    Moon moon;
    moon.direction = from_elevation_azimuth(30.0, 120.0);
    moon.sun_from_moon = sun_from_moon(moon.direction, 20.0);
    moon.irradiance_ratio = moon_irradiance_ratio(20.0, kMeanMoon_m, kAu_m);
    moon.disc = false;
    SkyImageOptions options;
    options.sun_disc = false;
    const SkyImage night = render_equirect_sky_with_moon(*method, atm, o, moon, 64, options);
    const SkyImage dark = render_equirect_sky(*method, atm, o, 64, options);
    Observer mo = o;
    mo.sun_direction = moon.direction;
    const SkyImage lit = render_equirect_sky(*method, atm, mo, 64, options);
    double max_rel = 0.0, sum = 0.0;
    for (std::size_t k = 0; k < night.pixels.size(); ++k) {
        const double expected = dark.pixels[k] + moon.irradiance_ratio * lit.pixels[k];
        max_rel =
            std::max(max_rel, std::abs(night.pixels[k] - expected) / std::max(1e-30, std::abs(expected)));
        sum += night.pixels[k];
    }
    EXPECT_LT(max_rel, 1e-6);
    EXPECT_GT(sum, 0.0);
    // And the moon's disc adds its energy on top.
    moon.disc = true;
    const SkyImage with_disc = render_equirect_sky_with_moon(*method, atm, o, moon, 64, options);
    double added = 0.0;
    for (std::size_t k = 0; k < night.pixels.size(); ++k) added += with_disc.pixels[k] - night.pixels[k];
    EXPECT_GT(added, 0.0);
}

// One pass for two suns (render_equirect_sky with an ExtraSun, what the moonlit sky uses)
// equals the sum of two separate renders, pixel by pixel, up to float rounding: RGB with
// the default four wavelengths (converted and gamut-mapped per sun: a twilight sun's sky
// has out-of-gamut pixels), three wavelengths (converted in place) and spectral, with and
// without the lit ground.
TEST(Moonlight, ExtraSunIsTheSumOfSeparateRenders) {
    const auto method = make_sky_method("lut");
    const Atmosphere four = Atmosphere::preset("clear_day");
    const Atmosphere three = Atmosphere::preset("bruneton2017", {680.0, 550.0, 440.0});
    const ExtraSun moon{from_elevation_azimuth(25.0, 200.0), 2.5e-6};
    for (const Atmosphere* atm : {&four, &three})
        for (double sun_elevation : {30.0, -4.0})
            for (auto output : {SkyImageOptions::Output::Rgb, SkyImageOptions::Output::Spectral})
                for (bool ground : {true, false}) {
                    Observer o;
                    o.sun_direction = from_elevation_azimuth(sun_elevation, 10.0);
                    SkyImageOptions options;
                    options.output = output;
                    options.ground = ground;
                    options.exposure = 3.0;
                    const SkyImage both =
                        render_equirect_sky(*method, *atm, o, std::span(&moon, 1), 64, options);
                    const SkyImage sun = render_equirect_sky(*method, *atm, o, 64, options);
                    Observer mo = o;
                    mo.sun_direction = moon.direction;
                    SkyImageOptions moon_options = options;
                    moon_options.sun_disc = false;
                    const SkyImage lit = render_equirect_sky(*method, *atm, mo, 64, moon_options);
                    ASSERT_EQ(both.pixels.size(), sun.pixels.size());
                    double max_rel = 0.0, moon_share = 0.0;
                    for (std::size_t k = 0; k < both.pixels.size(); ++k) {
                        const double m = moon.irradiance_scale * lit.pixels[k];
                        const double expected = sun.pixels[k] + m;
                        max_rel =
                            std::max(max_rel, std::abs(both.pixels[k] - expected) /
                                                  std::max(1e-30, std::abs(sun.pixels[k]) + std::abs(m)));
                        moon_share = std::max(moon_share, std::abs(m) / std::max(1e-30, std::abs(expected)));
                    }
                    EXPECT_LT(max_rel, 1e-6) << atm->channels() << " wavelengths, sun " << sun_elevation;
                    EXPECT_GT(moon_share, 1e-9);  // the moon's part is there, not rounded away
                }
    // Not with clouds; bad extra suns are named.
    using test::parameter_of;
    const Observer o;
    EXPECT_EQ(parameter_of([&] {
                  const ExtraSun bad{{0.0, 0.0, 0.0}, 1.0};
                  render_equirect_sky(*method, four, o, std::span(&bad, 1), 16);
              }),
              "extra_suns");
    EXPECT_EQ(parameter_of([&] {
                  const ExtraSun bad{{0.0, 0.0, 1.0}, -1.0};
                  render_equirect_sky(*method, four, o, std::span(&bad, 1), 16);
              }),
              "extra_suns");
}

// The disc as a formula (moon_disc_model, drawn by hosts from the view direction): the
// far-away Lommel-Seeliger law's integral over the disc is the closed form
// moon_disc_relative_integral_far (quadrature in polar coordinates about the centre, within
// 1e-4 at phases 0-150 degrees), close to the exact finite-distance law's (within 3 %, the
// difference of order the angular radius, largest at thin crescents); and the model's
// radiance integrates to the moon's irradiance through the air, E_sun ratio T.
TEST(Moonlight, DiscModelIntegratesToTheIrradiance) {
    const std::array<double, 3> m{0.0, 0.0, 1.0};
    const double radius = 0.259 * kDegree;
    for (double alpha : {0.0, 30.0, 90.0, 150.0}) {
        const double a = alpha * kDegree;
        const std::array<double, 3> s{std::sin(a), 0.0, -std::cos(a)};
        // Over theta in [0, pi/2) with sin(rho) = sin(radius) sin(theta) (mu = cos theta
        // on the far form's disc: smooth to the limb), psi around:
        // dOmega = sin(rho) sin(radius) cos(theta) / cos(rho) dtheta dpsi.
        const int nt = 600, np = 1200;
        double far = 0.0, exact = 0.0;
        for (int i = 0; i < nt; ++i) {
            const double theta = 0.5 * kPi * (i + 0.5) / nt;
            const double rho = std::asin(std::sin(radius) * std::sin(theta));
            const double w = std::sin(rho) * std::sin(radius) * std::cos(theta) / std::cos(rho) *
                             (0.5 * kPi / nt) * (kTwoPi / np);
            for (int k = 0; k < np; ++k) {
                const double psi = kTwoPi * (k + 0.5) / np;
                const std::array<double, 3> v{std::sin(rho) * std::cos(psi), std::sin(rho) * std::sin(psi),
                                              std::cos(rho)};
                far += moon_disc_relative_radiance_far(v, m, radius, s) * w;
                exact += moon_disc_relative_radiance(v, m, radius, s) * w;
            }
        }
        const double closed = moon_disc_relative_integral_far(a, radius);
        EXPECT_NEAR(far / closed, 1.0, 1e-4) << "phase " << alpha;
        EXPECT_NEAR(exact / closed, 1.0, 0.03) << "phase " << alpha;
    }
    EXPECT_NEAR(moon_disc_relative_integral_far(0.0, radius), 0.5 * kPi * std::pow(std::sin(radius), 2),
                1e-15);
    EXPECT_EQ(moon_disc_relative_integral_far(kPi, radius), 0.0);

    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    Moon moon;
    moon.direction = from_elevation_azimuth(35.0, 80.0);
    moon.angular_radius_rad = radius;
    moon.sun_from_moon = sun_from_moon(moon.direction, 70.0);
    moon.irradiance_ratio = moon_irradiance_ratio(70.0, kMeanMoon_m, kAu_m);
    const MoonDiscModel model = moon_disc_model(atm, Observer{}, moon);
    EXPECT_NEAR(model.phase_angle_rad / kDegree, 70.0, 1e-9);
    Observer mo;
    mo.sun_direction = moon.direction;
    Atmosphere moon_atm = atm;
    moon_atm.sun_angular_radius_rad = radius;
    const SunRadiometry air = sun_radiometry(moon_atm, mo.validated());
    for (std::size_t c = 0; c < atm.channels(); ++c)
        EXPECT_NEAR(model.radiance_scale[c] * model.relative_integral_sr /
                        (atm.solar_irradiance[c] * moon.irradiance_ratio * air.transmittance[c]),
                    1.0, 1e-12);
}

TEST(Moonlight, BadInputNamesTheParameter) {
    using test::parameter_of;
    EXPECT_EQ(parameter_of([] { moon_v_magnitude(181.0); }), "phase_angle_deg");
    EXPECT_EQ(parameter_of([] { moon_v_magnitude(NAN); }), "phase_angle_deg");
    EXPECT_EQ(parameter_of([] { moon_irradiance_ratio(0.0, 1.0, kAu_m); }), "moon_distance_m");
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    Moon moon;
    moon.irradiance_ratio = -1.0;
    EXPECT_EQ(
        parameter_of([&] { moon_disc_pixels(atm, Observer{}, moon, 16, SkyImageOptions::Output::Rgb); }),
        "moon.irradiance_ratio");
    moon.irradiance_ratio = 1e-6;
    moon.direction = {NAN, 0.0, 1.0};
    EXPECT_EQ(
        parameter_of([&] { moon_disc_pixels(atm, Observer{}, moon, 16, SkyImageOptions::Output::Rgb); }),
        "moon.direction");
    moon.direction = {0.0, 0.0, 1.0};
    EXPECT_EQ(
        parameter_of([&] { moon_disc_pixels(atm, Observer{}, moon, 15, SkyImageOptions::Output::Rgb); }),
        "width");
}

// The moon's sky is left out beyond kMoonSkyDepressionDeg: the sky of a sun just below that
// depression, times the brightest moon's irradiance ratio (full moon at perigee, < 3e-6),
// is under 1e-4 of the night glow everywhere above the horizon (the most just above the
// horizon below the sun; at the zenith far less).
TEST(MoonlitSky, LeftOutBelowTheDepressionLimitIsNegligible) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const auto method = make_sky_method("lut", SkyOptions{});
    Observer o;
    o.sun_direction = from_elevation_azimuth(-kMoonSkyDepressionDeg - 1e-3, 0.0);
    SkyImageOptions options;
    options.sun_disc = false;
    const int width = 256, height = 128;
    const SkyImage sky = render_equirect_sky(*method, atm, o.validated(), width, options);
    const std::vector<float> glow =
        night_glow_pixels(atm, o.validated(), width, SkyImageOptions::Output::Rgb);
    double worst = 0.0;
    for (int j = 0; j < height / 2; ++j)
        for (int i = 0; i < width; ++i) {
            // Per pixel, over the three channels (near the horizon the deep red glow's blue
            // is gamut-mapped to 0).
            double s = 0.0, g = 0.0;
            for (std::size_t c = 0; c < 3; ++c) {
                const std::size_t k = (std::size_t(j) * width + std::size_t(i)) * 3 + c;
                s += sky.pixels[k];
                g += glow[k];
            }
            ASSERT_GT(g, 0.0) << "row " << j;
            worst = std::max(worst, 3e-6 * s / g);
        }
    std::printf("moon's sky below the limit / night glow: at most %.3g\n", worst);
    EXPECT_LT(worst, 1e-4);
}

}  // namespace
}  // namespace welkin
