// SPDX-License-Identifier: Apache-2.0
// The lit ground below the horizon (ground.hpp, sky_image.hpp "The ground"): the closed
// form without air, the switch, and the horizon.
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/ground.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/sky/method.hpp"

using namespace welkin;

namespace {

// A preset with every coefficient zero: no air, so T = 1, no path radiance, no sky light.
Atmosphere airless() {
    Atmosphere a = Atmosphere::preset("clear");
    for (auto* v : {&a.rayleigh_scattering, &a.mie_scattering, &a.mie_extinction, &a.absorption_extinction})
        std::fill(v->begin(), v->end(), 0.0);
    return a;
}

glm::dvec3 sun_at(double elevation_deg) {
    const double e = elevation_deg * kPi / 180.0;
    return {std::cos(e), 0.0, std::sin(e)};
}

}  // namespace

// Without air the ground's radiance is albedo / pi * E_0 * mu_s at the ground point.
TEST(Ground, AirlessGroundIsLambertianUnderTheSun) {
    const Atmosphere atm = airless();
    const GroundIllumination light(atm);
    std::vector<double> e(atm.channels()), sky(atm.channels());
    for (double mu_s : {1.0, 0.7, 0.3, 0.05}) {
        light.irradiance(mu_s, e);
        light.sky_irradiance(mu_s, sky);
        for (std::size_t c = 0; c < atm.channels(); ++c) {
            EXPECT_NEAR(e[c], atm.solar_irradiance[c] * mu_s, 1e-9 * atm.solar_irradiance[c]) << mu_s;
            EXPECT_EQ(sky[c], 0.0);
        }
    }
    // The image: observer 10 km up, albedo 0.3, views below the horizon.
    const Observer obs{10000.0, sun_at(40.0)};
    SkyImageOptions options;
    options.output = SkyImageOptions::Output::Spectral;
    options.sun_disc = false;
    options.ground_albedo = 0.3;
    const int W = 64, H = 32;
    const SkyImage image = render_equirect_sky(*make_sky_method("lut"), atm, obs, W, options);
    const double r = atm.bottom_radius_m + obs.altitude_m;
    int checked = 0;
    for (int j = H / 2 + 1; j < H; ++j)
        for (int i = 0; i < W; i += 7) {
            const glm::dvec3 d = equirect_pixel_direction(i, j, W, H);
            const double t =
                -r * d.z - std::sqrt(r * r * d.z * d.z - (r * r - atm.bottom_radius_m * atm.bottom_radius_m));
            const glm::dvec3 p = glm::dvec3(0, 0, r) + t * d;
            const double mu_s = glm::dot(glm::normalize(p), obs.sun_direction);
            for (std::size_t c = 0; c < atm.channels(); ++c) {
                const double want = 0.3 / kPi * atm.solar_irradiance[c] * std::max(mu_s, 0.0);
                const float got = image.pixels[(std::size_t(j) * W + i) * atm.channels() + c];
                EXPECT_NEAR(got, want, 2e-4 * atm.solar_irradiance[c]) << i << " " << j;
            }
            ++checked;
        }
    EXPECT_GT(checked, 50);
}

// Switched off, below the horizon is what the method gives alone: black from the ground.
TEST(Ground, SwitchOffGivesTheBlackGround) {
    const Atmosphere atm = Atmosphere::preset("clear");
    const Observer obs{0.0, sun_at(10.0)};
    SkyImageOptions off, on;
    off.ground = false;
    const int W = 64, H = 32;
    const auto lut = make_sky_method("lut");
    const SkyImage a = render_equirect_sky(*lut, atm, obs, W, off);
    const SkyImage b = render_equirect_sky(*lut, atm, obs, W, on);
    for (int j = H / 2; j < H; ++j)
        for (int i = 0; i < W; ++i)
            for (int c = 0; c < 3; ++c) {
                const std::size_t k = (std::size_t(j) * W + i) * 3 + c;
                EXPECT_EQ(a.pixels[k], 0.0f);
                EXPECT_GT(b.pixels[k], 0.0f);
            }
    // Above the horizon both are the same sky.
    for (std::size_t k = 0; k < std::size_t(H / 2) * W * 3; ++k) EXPECT_EQ(a.pixels[k], b.pixels[k]);
}

TEST(Ground, AlbedoOutOfRangeIsRefused) {
    SkyImageOptions o;
    o.ground_albedo = 1.5;
    EXPECT_THROW(o.validate(), InvalidArgument);
}

// At the horizon: from the ground, lit ground right below it (no black band: the rows next
// to the horizon change smoothly; the sky above is brighter than a ground of albedo 0.1
// under a low sun, a real edge); from higher up, where the ground near the horizon is seen
// through the same long air path as the sky just above it, continuity across the horizon
// (the path radiance dominates both).
TEST(Ground, HorizonIsContinuous) {
    const Atmosphere atm = Atmosphere::preset("clear");
    const auto lut = make_sky_method("lut");
    for (double altitude : {0.0, 5000.0, 20000.0}) {
        const Observer obs{altitude, sun_at(10.0)};
        const double dip = -std::acos(atm.bottom_radius_m / (atm.bottom_radius_m + altitude));
        // The rows next to the horizon's row in a 512-wide image (0.35 degrees each).
        const int W = 512, H = 256;
        SkyImageOptions options;
        options.sun_disc = false;
        const SkyImage img = render_equirect_sky(*lut, atm, obs, W, options);
        const int j_h = int(std::floor((0.5 * kPi - dip) / (kPi / H)));  // row holding the horizon
        for (int i = 0; i < W; i += 128) {
            const float* up = &img.pixels[(std::size_t(j_h - 1) * W + i) * 3];
            const float* down = &img.pixels[(std::size_t(j_h + 1) * W + i) * 3];
            const double yu = 0.2126 * up[0] + 0.7152 * up[1] + 0.0722 * up[2];
            const double yd = 0.2126 * down[0] + 0.7152 * down[1] + 0.0722 * down[2];
            const float* down2 = &img.pixels[(std::size_t(j_h + 2) * W + i) * 3];
            const double yd2 = 0.2126 * down2[0] + 0.7152 * down2[1] + 0.0722 * down2[2];
            EXPECT_GT(yd, 0.0) << altitude << " " << i;
            if (altitude == 0.0) {
                EXPECT_NEAR(yd2, yd, 0.1 * yd) << altitude << " " << i;
            }
            if (altitude > 0.0) {
                EXPECT_NEAR(yd, yu, 0.5 * yu) << altitude << " " << i;
            }
        }
    }
}

// The irradiance tables depend on the atmosphere alone: shared() hands the same tables to
// every image of an atmosphere (a sun change does not rebuild them), other ones to another
// atmosphere, and they equal freshly built ones exactly.
TEST(Ground, TablesAreSharedPerAtmosphereAndEqualFreshOnes) {
    const Atmosphere clear = Atmosphere::preset("clear");
    Atmosphere dusty = clear;
    for (auto* v : {&dusty.mie_scattering, &dusty.mie_extinction})
        for (double& c : *v) c *= 1.5;
    const auto a = GroundIllumination::shared(clear);
    EXPECT_EQ(GroundIllumination::shared(clear), a);
    const auto b = GroundIllumination::shared(dusty);
    EXPECT_NE(b, a);
    EXPECT_EQ(GroundIllumination::shared(clear), a);  // two atmospheres fit
    const GroundIllumination fresh(clear);
    std::vector<double> x(clear.channels()), y(clear.channels());
    for (double mu_s : {-0.3, -0.05, 0.0, 0.2, 0.7, 1.0}) {
        a->irradiance(mu_s, x);
        fresh.irradiance(mu_s, y);
        EXPECT_EQ(x, y) << mu_s;
    }
    std::vector<double> z(clear.channels());
    b->sky_irradiance(0.5, z);
    a->sky_irradiance(0.5, x);
    EXPECT_NE(x, z);
}
