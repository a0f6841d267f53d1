// SPDX-License-Identifier: Apache-2.0
// The clouds' transmittance towards a distant light (clouds/shadow.hpp).
#include <cmath>
#include <limits>
#include <vector>

#include "cloud_test_util.hpp"
#include <gtest/gtest.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/shadow.hpp"

using namespace welkin;

namespace {

// A slab of cloud 1000 m to 1800 m up, sigma_t 0.004 m^-1, wide enough for every ray here.
const test::HomogeneousBox kSlab({-1e6, -1e6, 1000.0}, {1e6, 1e6, 1800.0}, 0.004);

TEST(CloudShadow, SlabIsBeerLambertAlongTheSlantPath) {
    // Below the slab, towards a sun at elevation e: the path through it is 800 / sin(e) m,
    // T = exp(-0.004 x 800 / sin e). Above it: 1. Inside, at 1400 m: half the path.
    const std::vector<glm::dvec3> points{{0, 0, 0}, {5000, -300, 2}, {0, 0, 2000}, {10, 20, 1400}};
    for (double e_deg : {90.0, 30.0, 10.0}) {
        const double e = e_deg * M_PI / 180.0;
        const glm::dvec3 sun{std::cos(e), 0.0, std::sin(e)};
        const std::vector<float> t = cloud_transmittance(kSlab, points, 3.0 * sun);  // not unit
        const double below = std::exp(-0.004 * 800.0 / std::sin(e));
        EXPECT_NEAR(t[0], below, 1e-6 * below + 1e-7) << e_deg;
        EXPECT_NEAR(t[1], below, 1e-6 * below + 1e-7) << e_deg;
        EXPECT_EQ(t[2], 1.0f) << e_deg;
        const double inside = std::exp(-0.004 * 400.0 / std::sin(e));
        EXPECT_NEAR(t[3], inside, 1e-6 * inside) << e_deg;
    }
}

TEST(CloudShadow, AwayFromTheCloudIsOne) {
    // A box 2 km wide over x in [-1000, 1000]: a point whose ray towards the zenith misses
    // it is unshadowed, one under it is shadowed.
    const test::HomogeneousBox box({-1000, -1000, 1000}, {1000, 1000, 1800}, 0.004);
    const std::vector<glm::dvec3> points{{0, 0, 0}, {5000, 0, 0}};
    const std::vector<float> t = cloud_transmittance(box, points, {0, 0, 1});
    EXPECT_NEAR(t[0], std::exp(-3.2), 1e-6);
    EXPECT_EQ(t[1], 1.0f);
}

TEST(CloudShadow, BadInputNamesTheParameter) {
    const std::vector<glm::dvec3> p{{0, 0, 0}};
    const std::vector<glm::dvec3> nan{{0, std::numeric_limits<double>::quiet_NaN(), 0}};
    auto names = [](auto f, const char* parameter) {
        try {
            f();
            ADD_FAILURE() << "no error for " << parameter;
        } catch (const InvalidArgument& e) {
            EXPECT_EQ(e.parameter(), parameter);
        }
    };
    names([&] { cloud_transmittance(kSlab, p, {0, 0, 0}); }, "direction");
    names([&] { cloud_transmittance(kSlab, nan, {0, 0, 1}); }, "points");
    names([&] { cloud_transmittance(kSlab, p, {0, 0, 1}, {.steps = 0}); }, "steps");
    names(
        [&] {
            cloud_transmittance(kSlab, p, {0, 0, 1}, {.steps = 8, .max_distance_m = -1});
        },
        "max_distance_m");
}

}  // namespace
