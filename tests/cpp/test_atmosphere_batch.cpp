// SPDX-License-Identifier: Apache-2.0
// The density table of AtmosphereBatch (atmosphere/batch.hpp): kTableSize entries evenly
// spaced in s = r^2 - R^2, interpolated linearly in s. For f(s) = exp(-h(s) / H) with
// h(s) = sqrt(R^2 + s) - R, linear interpolation on nodes ds apart errs by at most
// ds^2 / 8 max |f''|, and f'' = f [1 / (2 r H)]^2 (1 + H / r) (h' = 1 / 2r, h'' = -1 / 4r^3),
// so relative to f the bound is dh^2 / (8 H^2) (1 + H / R) with dh = ds / 2R the largest
// spacing in altitude (at the ground). The tests hold every preset's Rayleigh and Mie
// coefficients to that bound (plus float rounding) at altitudes between the nodes, and
// the compact extinction table the graded quadrature reads to the full one.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/batch.hpp"
#include "welkin/atmosphere/inscattering.hpp"
#include "welkin/atmosphere/skyview_lut.hpp"

using namespace welkin;

namespace {

// The scale height of a profile that is one exponential layer, or 0.
double scale_height(const DensityProfile& p) {
    if (p.layers().size() != 1) return 0.0;
    const DensityLayer& l = p.layers().front();
    if (l.exp_term == 0.0 || l.exp_scale_per_m >= 0.0 || l.linear_per_m != 0.0 || l.constant != 0.0)
        return 0.0;
    return -1.0 / l.exp_scale_per_m;
}

}  // namespace

TEST(AtmosphereBatch, DensityTableIsWithinItsInterpolationBoundFromTheGroundToTheTop) {
    for (const char* name : {"bruneton2017", "clear", "hazy", "polluted", "mars"}) {
        const Atmosphere atm = Atmosphere::preset(name);
        const AtmosphereBatch batch(atm, 0, 3);
        const double R = atm.bottom_radius_m, top = atm.top_radius_m;
        const double dh = (top - R) * (top + R) / double(AtmosphereBatch::kTableSize - 1) / (2.0 * R);
        struct Constituent {
            const char* what;
            const DensityProfile& profile;
            const std::vector<double>& coefficient;
            Spectrum4 MediumSample::*field;
        };
        for (const Constituent& k :
             {Constituent{"rayleigh", atm.rayleigh_density, atm.rayleigh_scattering,
                          &MediumSample::rayleigh_scattering},
              Constituent{"mie", atm.mie_density, atm.mie_scattering, &MediumSample::mie_scattering}}) {
            const double H = scale_height(k.profile);
            if (H == 0.0) continue;  // not a single exponential: no closed-form bound
            const double bound = dh * dh / (8.0 * H * H) * (1.0 + H / R) + 3e-7;  // + float rounding
            double worst = 0.0;
            // 10^5 altitudes, none on a node (an irrational step), and the ends.
            for (int n = 0; n <= 100000; ++n) {
                const double h = std::min((top - R) * std::fmod(n * 0.6180339887498949, 1.0), top - R);
                const MediumSample m = batch.sample(h);
                for (int c = 0; c < 3; ++c) {
                    const double exact = k.coefficient[std::size_t(c)] * k.profile.density(h);
                    if (!(exact > 1e-30)) continue;
                    worst = std::max(worst, std::abs(double((m.*k.field)[c]) - exact) / exact);
                }
            }
            std::printf("[ %s %s ] H %.0f m: worst relative error %.2e, bound %.2e\n", name, k.what, H, worst,
                        bound);
            EXPECT_LE(worst, bound) << name << ' ' << k.what;
        }
    }
}

TEST(AtmosphereBatch, CompactExtinctionTableMatchesTheFullOneOnTheSquaredRadiusAxis) {
    for (const char* name : {"bruneton2017", "polluted", "mars"}) {
        const Atmosphere atm = Atmosphere::preset(name);
        const AtmosphereBatch batch(atm, 0, 3);
        const double R = atm.bottom_radius_m, top = atm.top_radius_m;
        for (double h : {0.0, 0.5, 7.0, 999.9, 10e3, 25e3 + 0.3, 40e3 - 0.3, top - R - 1.0}) {
            const double r = R + h;
            const double x =
                std::min((r - R) * (r + R) * batch.inv_table_step(), double(AtmosphereBatch::kTableSize - 1));
            const int i = std::min(int(x), AtmosphereBatch::kTableSize - 2);
            const Float4 compact = batch.extinction_at(i, float(x - double(i)));
            const Spectrum4 full = batch.sample(h).extinction;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(compact[c], full[c], 1e-6 * full[c] + 1e-20) << name << " h " << h;
        }
    }
}

// Looking below the horizon from the ground itself, a ray crosses no air: it gets no
// steps (not steps of weight zero), and the sky-view texels there are exactly zero.
TEST(AtmosphereBatch, RaysOfNoLengthFromTheGroundHaveNoStepsAndNoRadiance) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const AtmosphereBatch batch(atm, 0, 3);
    const double R = atm.bottom_radius_m;
    RaySamples ray;
    prepare_ray(batch, R, -0.3, 30, ray);
    EXPECT_TRUE(ray.steps.empty());
    EXPECT_EQ(ray.transmittance, Spectrum4(1.0f));
    prepare_ray(batch, R + 0.5, -0.3, 30, ray);  // half a metre up there is air below
    EXPECT_EQ(ray.steps.size(), 30u);

    const TransmittanceLut t(batch, 256, 64);
    const MultiScatteringLut ms(batch, t, 32);
    const SkyViewLut sky(batch, t, ms, R, 0.3, 192, 108);
    for (int j = 0; j < 108; ++j)
        for (int i = 0; i < 192; ++i) {
            const Spectrum4 L = sky.texture().at(i, j);
            for (int c = 0; c < 3; ++c) {
                ASSERT_TRUE(std::isfinite(L[c]));
                if (j >= 54)
                    EXPECT_EQ(L[c], 0.0f) << "row " << j;  // below the horizon
                else
                    EXPECT_GT(L[c], 0.0f) << "row " << j;
            }
        }
}
