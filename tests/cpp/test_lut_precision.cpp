// SPDX-License-Identifier: Apache-2.0
// The LUT builds look the sun's transmittance up in float from per-radius constants
// formed in double (TransmittanceLut::AtRadius). Planet-scale geometry is where float
// loses digits (r^2 - R^2 near the ground), so these tests hold the float lookup to the
// double one, TransmittanceLut::to_sun(r, mu_s), from half a metre above the ground to
// the top, with the sun around the horizon (grazing rays) and everywhere else.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "welkin/atmosphere/transmittance_lut.hpp"

using namespace welkin;

TEST(LutPrecision, FloatSunLookupMatchesTheDoubleOneFromHalfAMetreToTheTop) {
    for (const char* name : {"bruneton2017", "mars"}) {
        const Atmosphere atm = Atmosphere::preset(name);
        const AtmosphereBatch batch(atm, 0, 3);
        const TransmittanceLut lut(batch, 256, 64);
        const double R = atm.bottom_radius_m, top = atm.top_radius_m;
        double worst = 0.0;
        for (double h : {0.0, 0.5, 10.0, 1000.0, 20e3, top - R - 1.0, top - R}) {
            const double r = R + h;
            const TransmittanceLut::AtRadius at = lut.at_radius(r);
            const double cos_horizon = -std::sqrt(std::max(1.0 - (R / r) * (R / r), 0.0));
            for (int k = -2000; k <= 2000; ++k) {
                // Dense around the horizon (1e-6 steps over +-2e-3), then the whole range.
                for (double mu_s : {cos_horizon + 1e-6 * k, k / 2000.0}) {
                    if (mu_s < -1.0 || mu_s > 1.0) continue;
                    const Spectrum4 a = lut.to_sun(r, mu_s);
                    const Spectrum4 b = TransmittanceLut::to_sun(at, float(mu_s));
                    for (int c = 0; c < 3; ++c) {
                        // Relative where the sun is visible; absolute (to 1) where the
                        // visible fraction runs to zero across the horizon.
                        const double err =
                            std::abs(double(b[c]) - double(a[c])) / std::max(double(a[c]), 1e-2);
                        worst = std::max(worst, err);
                        ASSERT_TRUE(std::isfinite(b[c]));
                    }
                }
            }
        }
        std::printf("%s: float vs double sun lookup, worst difference %.2e\n", name, worst);
        EXPECT_LT(worst, 1e-4) << name;
    }
}
