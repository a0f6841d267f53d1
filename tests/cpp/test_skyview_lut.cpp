// SPDX-License-Identifier: Apache-2.0
// SkyViewLut's lookups (skyview_lut.hpp): the branch-free zenith angle against std::acos,
// and the block lookup of many views against one call per view.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "peer_table.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/atmosphere/skyview_lut.hpp"

using namespace welkin;

TEST(SkyViewLut, ZenithAngleIsWithinItsBoundOfAcos) {
    double worst = 0.0, at = 0.0;
    // Dense over [-1, 1], denser near the poles and the switch at |mu| = 1/2.
    std::vector<double> mus = {
        -1.0, -0.5, 0.0, 0.5, 1.0, std::nextafter(0.5, 1.0), std::nextafter(-0.5, -1.0)};
    for (int k = 0; k <= 2000000; ++k) mus.push_back(-1.0 + 2.0 * k / 2000000.0);
    for (int k = 0; k <= 100000; ++k) {
        mus.push_back(1.0 - 1e-9 * k);
        mus.push_back(-1.0 + 1e-9 * k);
        mus.push_back(0.5 + 1e-9 * (k - 50000));
    }
    for (double mu : mus) {
        const double e = std::abs(SkyViewLut::zenith_angle(mu) - std::acos(mu));
        if (e > worst) worst = e, at = mu;
    }
    std::printf("zenith_angle: worst |error| %.2e rad at mu = %.9f\n", worst, at);
    EXPECT_LT(worst, 1e-8);
}

// Callers reject zero and non-finite directions (LutSky validates them); the block lookup
// still stays inside its texture for them.
TEST(SkyViewLut, BlockLookupStaysInsideTheTextureForDirectionsCallersReject) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const AtmosphereBatch batch(atm, 0, 3);
    const TransmittanceLut t(batch, 256, 64);
    const MultiScatteringLut ms(batch, t, 32);
    const SkyViewLut sky(batch, t, ms, atm.bottom_radius_m, 0.5, 192, 108);
    const double nan = std::nan(""), inf = INFINITY;
    const std::vector<glm::dvec3> dirs = {{0, 0, 0}, {nan, 0, 1}, {0, 0, nan}, {inf, 0, 0}, {0, -inf, 1}};
    std::vector<float> out(dirs.size() * 3);
    sky.radiance(dirs, glm::normalize(glm::dvec3(1.0, 0.0, 1.0)), 3, out.data(), 3);
    for (float x : out) EXPECT_TRUE(std::isfinite(x));
}

TEST(SkyViewLut, BlockLookupEqualsOneLookupPerView) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const AtmosphereBatch batch(atm, 0, 3);
    const TransmittanceLut t(batch, 256, 64);
    const MultiScatteringLut ms(batch, t, 32);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> g;
    for (const glm::dvec3 sun : {glm::normalize(glm::dvec3(0.5, 0.3, 0.4)), glm::dvec3(0.0, 0.0, 1.0),
                                 glm::normalize(glm::dvec3(-1.0, 0.2, -0.05))}) {
        for (double altitude : {0.0, 0.5, 1000.0, 59e3}) {
            const SkyViewLut sky(batch, t, ms, atm.bottom_radius_m + altitude, sun.z, 192, 108);
            // Random views (unnormalised; the API takes non-zero ones), the poles, the
            // horizon, the sun and its opposite, the horizon below the sun.
            std::vector<glm::dvec3> dirs = {
                {0, 0, 1}, {0, 0, -3}, {1, 0, 0}, {0, 2, 1e-9}, sun, -sun, {sun.x + 1e-3, sun.y, 0.0}};
            for (int k = 0; k < 5000; ++k) dirs.push_back({g(rng), g(rng), g(rng)});
            std::vector<float> block(dirs.size() * 3);
            sky.radiance(dirs, sun, 3, block.data(), 3);
            for (std::size_t k = 0; k < dirs.size(); ++k) {
                const glm::dvec3 v = dirs[k] / std::sqrt(glm::dot(dirs[k], dirs[k]));
                const double hv2 = v.x * v.x + v.y * v.y, hs2 = sun.x * sun.x + sun.y * sun.y;
                const double cos_phi =
                    (hv2 > 1e-24 && hs2 > 1e-24)
                        ? std::clamp((v.x * sun.x + v.y * sun.y) / std::sqrt(hv2 * hs2), -1.0, 1.0)
                        : 1.0;
                const Spectrum4 one = sky.radiance(v.z, cos_phi);
                for (int c = 0; c < 3; ++c) {
                    ASSERT_TRUE(std::isfinite(block[k * 3 + c]));
                    // The two forms round the normalisation alike only to a few ulps.
                    ASSERT_NEAR(block[k * 3 + c], one[c], 2e-6f * std::abs(one[c]) + 1e-30f) << "view " << k;
                }
            }
        }
    }
}
