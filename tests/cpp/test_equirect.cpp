// SPDX-License-Identifier: Apache-2.0
// Blender's equirectangular mapping: landmarks, round trips, pixel centres, solid angles.
#include <cmath>
#include <random>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/base/equirect.hpp"
#include "welkin/base/math.hpp"

using namespace welkin;

namespace {

// Cycles' own form (intern/cycles/kernel/camera/projection.h):
// direction_to_equirectangular_range(dir, range = (-2 pi, pi, -pi, pi)), written out
// independently of src/base/equirect.cpp.
glm::dvec2 cycles_direction_to_equirectangular(const glm::dvec3& dir) {
    const double range[4] = {-kTwoPi, kPi, -kPi, kPi};
    const double u = (std::atan2(dir.y, dir.x) - range[1]) / range[0];
    const double v = (std::acos(dir.z / glm::length(dir)) - range[3]) / range[2];
    return {u, v};
}

}  // namespace

TEST(Equirect, Landmarks) {
    const auto uv = [](double x, double y, double z) { return direction_to_equirect({x, y, z}); };
    EXPECT_NEAR(uv(1, 0, 0).x, 0.5, 1e-15);  // +X: the image centre
    EXPECT_NEAR(uv(1, 0, 0).y, 0.5, 1e-15);
    EXPECT_NEAR(uv(0, 1, 0).x, 0.25, 1e-15);  // +Y: a quarter from the left
    EXPECT_NEAR(uv(0, -1, 0).x, 0.75, 1e-15);
    EXPECT_NEAR(uv(-1, 0, 0).x, 0.0, 1e-15);        // -X: the left edge, u in [0, 1)
    EXPECT_NEAR(uv(-1, -1e-300, 0).x, 0.0, 1e-15);  // below the branch cut: folded to 0
    EXPECT_LT(uv(-1, -1e-300, 0).x, 1.0);
    EXPECT_NEAR(uv(0, 0, 1).y, 1.0, 1e-15);   // zenith: top (v = 1)
    EXPECT_NEAR(uv(0, 0, -1).y, 0.0, 1e-15);  // nadir: bottom
    EXPECT_NEAR(uv(1, 0, 1).y, 0.75, 1e-15);  // 45 degrees up
}

TEST(Equirect, MatchesCyclesFormula) {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n;
    for (int k = 0; k < 10000; ++k) {
        const glm::dvec3 d = glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
        const glm::dvec2 a = direction_to_equirect(d), b = cycles_direction_to_equirectangular(d);
        EXPECT_NEAR(a.x, b.x, 1e-12);
        EXPECT_NEAR(a.y, b.y, 1e-7);  // acos loses digits near the poles; atan2 does not
    }
}

TEST(Equirect, RoundTrips) {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (int k = 0; k < 10000; ++k) {
        const glm::dvec3 d = glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
        const glm::dvec3 back = equirect_to_direction(direction_to_equirect(d));
        EXPECT_NEAR(glm::length(back - d), 0.0, 1e-14);
        const glm::dvec2 uv{u01(rng), 0.001 + 0.998 * u01(rng)};
        const glm::dvec2 uv2 = direction_to_equirect(equirect_to_direction(uv));
        EXPECT_NEAR(uv2.x, uv.x, 1e-13);
        EXPECT_NEAR(uv2.y, uv.y, 1e-13);
    }
}

TEST(Equirect, PixelCentresTopRowFirst) {
    const int W = 64, H = 32;
    // Top-left pixel: half a pixel from the zenith and from the left edge.
    const glm::dvec2 tl = direction_to_equirect(equirect_pixel_direction(0, 0, W, H));
    EXPECT_NEAR(tl.x, 0.5 / W, 1e-14);
    EXPECT_NEAR(tl.y, 1.0 - 0.5 / H, 1e-14);
    const glm::dvec3 top = equirect_pixel_direction(5, 0, W, H);
    EXPECT_NEAR(std::asin(top.z), 0.5 * kPi - 0.5 * kPi / H, 1e-12);
    const glm::dvec3 bottom = equirect_pixel_direction(5, H - 1, W, H);
    EXPECT_NEAR(std::asin(bottom.z), -0.5 * kPi + 0.5 * kPi / H, 1e-12);
    // The two middle columns straddle +X; the two middle rows straddle the horizon.
    const glm::dvec3 a = equirect_pixel_direction(W / 2 - 1, H / 2 - 1, W, H);
    const glm::dvec3 b = equirect_pixel_direction(W / 2, H / 2, W, H);
    EXPECT_GT(a.y, 0.0);  // left of centre is towards +Y (u decreases with atan2)
    EXPECT_LT(b.y, 0.0);
    EXPECT_GT(a.z, 0.0);
    EXPECT_LT(b.z, 0.0);
    EXPECT_NEAR(a.y, -b.y, 1e-15);
    // +Y lies between columns W/4 - 1 (towards -X, the left edge) and W/4 (towards +X).
    EXPECT_LT(equirect_pixel_direction(W / 4 - 1, H / 2, W, H).x, 0.0);
    EXPECT_GT(equirect_pixel_direction(W / 4, H / 2, W, H).x, 0.0);
}

TEST(Equirect, PixelSolidAnglesSumToTheSphere) {
    for (int W : {4, 64, 2048}) {
        const int H = W / 2;
        double sum = 0.0;
        for (int j = 0; j < H; ++j) sum += W * equirect_pixel_solid_angle(j, W, H);
        EXPECT_NEAR(sum, 4.0 * kPi, 1e-12) << W;
        // Symmetric about the horizon, largest at the horizon.
        EXPECT_NEAR(equirect_pixel_solid_angle(0, W, H), equirect_pixel_solid_angle(H - 1, W, H), 1e-15);
        // A row's solid angle approaches cos(e) dphi de at its centre.
        const int j = H / 3;
        const double e = std::asin(equirect_pixel_direction(0, j, W, H).z);
        EXPECT_NEAR(equirect_pixel_solid_angle(j, W, H) / (std::cos(e) * (kTwoPi / W) * (kPi / H)), 1.0,
                    2.0 / (double(W) * W));  // 1 - (pi/H)^2 / 24
    }
}
