// SPDX-License-Identifier: Apache-2.0
// simd.hpp: the four-lane exponential used for the transmittance LUT's texels, against
// std::exp in double over the range of arguments it is stated for.
#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>

#include "welkin/base/simd.hpp"

using namespace welkin;

TEST(SimdExp, WithinFloatEpsilonOfStdExpFromMinus87ToZero) {
    // Every float of [-87, 0] would be 1.1e9 values; a dense even grid (4M points, spacing
    // 2e-5, finer than the reduction's steps of ln 2 and crossing each of them many times)
    // plus the ends and the points k ln 2 where the reduced argument changes sign.
    double worst = 0.0, worst_x = 0.0;
    auto check = [&](float x) {
        const Float4 y = exp_nonpositive(Float4{x, x, x, x});
        const double exact = std::exp(double(x));
        for (int lane = 0; lane < 4; ++lane) {
            const double rel = std::abs(double(y[lane]) - exact) / exact;
            if (rel > worst) worst = rel, worst_x = x;
        }
    };
    const int n = 1 << 22;
    for (int i = 0; i <= n; ++i) check(float(-87.0 * double(i) / double(n)));
    for (int k = 0; k <= 125; ++k)
        for (float dx : {-1e-6f, 0.0f, 1e-6f}) check(float(-double(k) * std::log(2.0)) + dx);
    std::printf("exp_nonpositive: worst relative error %.3g (%.2f float epsilons) at x = %.6f\n", worst,
                worst / double(std::numeric_limits<float>::epsilon()), worst_x);
    EXPECT_LE(worst, double(std::numeric_limits<float>::epsilon()));  // 1.19e-7 (measured: 8.1e-8)
}

TEST(SimdExp, ExactAtZeroAndZeroBelowTheNormalFloats) {
    const Float4 y = exp_nonpositive(Float4{0.0f, -0.0f, -87.4f, -std::numeric_limits<float>::infinity()});
    EXPECT_EQ(y[0], 1.0f);
    EXPECT_EQ(y[1], 1.0f);
    EXPECT_EQ(y[2], 0.0f);
    EXPECT_EQ(y[3], 0.0f);
    // Just above the cut the result is still a normal float and accurate.
    const Float4 z = exp_nonpositive(Float4{-87.3f, -87.3f, -87.3f, -87.3f});
    EXPECT_GE(z[0], std::numeric_limits<float>::min());
    EXPECT_NEAR(double(z[0]) / std::exp(double(-87.3f)), 1.0, 2.4e-7);
}

TEST(SimdExp, LanesAreIndependent) {
    const Float4 x = {-0.1f, -3.0f, -20.0f, -60.0f};
    const Float4 y = exp_nonpositive(x);
    for (int lane = 0; lane < 4; ++lane) {
        const Float4 single = exp_nonpositive(Float4{x[lane], x[lane], x[lane], x[lane]});
        EXPECT_EQ(y[lane], single[0]);
    }
}
