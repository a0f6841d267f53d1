// SPDX-License-Identifier: Apache-2.0
// Optical depth: optical_depth.hpp's exact quadrature against closed forms and brute
// force, and the reference path tracer's column table (atmosphere/column_table.hpp)
// against optical_depth.hpp.
#include <cmath>
#include <cstdio>

#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/column_table.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/rng.hpp"

using namespace welkin;

namespace {

constexpr double kR = 6360e3;

// Midpoint sum of the profile's density along the ray, n steps.
double brute_force_integral(const DensityProfile& p, double r, double mu, double length, int n) {
    const double dt = length / n;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += p.density(radius_at(r, mu, (i + 0.5) * dt) - kR);
    return sum * dt;
}

}  // namespace

TEST(OpticalDepth, ExponentialLayerAlongVerticalRayMatchesClosedForm) {
    // int_h0^h1 exp(-h / H) dh = H (exp(-h0 / H) - exp(-h1 / H)).
    for (double H : {1200.0, 8000.0, 11100.0})
        for (double h0 : {0.0, 500.0, 5000.0, 30000.0})
            for (double h1 : {h0 + 10.0, h0 + 3000.0, 60000.0}) {
                if (!(h1 > h0)) continue;
                const DensityProfile p = DensityProfile::exponential(H);
                const double exact = H * (std::exp(-h0 / H) - std::exp(-h1 / H));
                // Upwards from h0, and downwards from h1 (mu = -1).
                EXPECT_NEAR(density_integral(p, kR, kR + h0, 1.0, h1 - h0) / exact, 1.0, 1e-9)
                    << "H " << H << " h0 " << h0 << " h1 " << h1;
                EXPECT_NEAR(density_integral(p, kR, kR + h1, -1.0, h1 - h0) / exact, 1.0, 1e-9)
                    << "H " << H << " h0 " << h0 << " h1 " << h1;
            }
}

TEST(OpticalDepth, ExponentialLayerAlongHorizontalRayMatchesBruteForce) {
    // Horizontal rays from the ground and from 5 km, to the top of a 60 km atmosphere,
    // and a ray descending past its lowest point: 1e6-step midpoint sums (relative error
    // ~1e-9 for these smooth integrands).
    const double top = kR + 60e3;
    for (double H : {1200.0, 8000.0}) {
        const DensityProfile p = DensityProfile::exponential(H);
        for (auto [h, mu] : {std::pair{0.0, 0.0}, std::pair{5000.0, 0.0}, std::pair{20000.0, -0.05}}) {
            const double r = kR + h;
            const double length = distance_to_boundary(r, mu, kR, top);
            const double exact = brute_force_integral(p, r, mu, length, 1000000);
            EXPECT_NEAR(density_integral(p, kR, r, mu, length) / exact, 1.0, 1e-7)
                << "H " << H << " h " << h << " mu " << mu;
        }
    }
}

TEST(OpticalDepth, TentLayerMatchesClosedFormAndBruteForce) {
    // The ozone tent (0 at 10 km, 1 at 25 km, 0 at 40 km) integrates to 15 km vertically;
    // from 17.5 km up it is int_17.5^25 (h - 10) / 15 dh + 7.5 = (15^2 - 7.5^2) / 30 + 7.5
    // (in km): the rest of the rising half plus the whole falling half.
    const DensityProfile tent = DensityProfile::tent(10e3, 25e3, 40e3);
    EXPECT_NEAR(density_integral(tent, kR, kR, 1.0, 60e3), 15e3, 1e-6);
    EXPECT_NEAR(density_integral(tent, kR, kR + 17.5e3, 1.0, 60e3),
                (15e3 * 15e3 - 7.5e3 * 7.5e3) / 30e3 + 7.5e3, 1e-6);
    // Slanted and grazing rays through the kinks.
    for (auto [h, mu] : {std::pair{0.0, 0.1}, std::pair{0.0, 0.0}, std::pair{30e3, -0.08}}) {
        const double r = kR + h;
        const double length = distance_to_boundary(r, mu, kR, kR + 60e3);
        const double exact = brute_force_integral(tent, r, mu, length, 1000000);
        EXPECT_NEAR(density_integral(tent, kR, r, mu, length) / exact, 1.0, 1e-7)
            << "h " << h << " mu " << mu;
    }
}

TEST(OpticalDepth, TransmittanceIsInUnitIntervalAndDecreasesWithPathLength) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    for (auto [h, mu] :
         {std::pair{0.0, 1.0}, std::pair{0.0, 0.01}, std::pair{10e3, -0.1}, std::pair{59e3, 0.0}}) {
        const double r = atm.bottom_radius_m + h;
        const double length = distance_to_boundary(r, mu, atm.bottom_radius_m, atm.top_radius_m);
        std::vector<double> previous(atm.channels(), 1.0);
        for (int i = 1; i <= 50; ++i) {
            const ColumnDensity col = column_density(atm, r, mu, length * i / 50.0);
            for (std::size_t c = 0; c < atm.channels(); ++c) {
                const double t = std::exp(-optical_depth(atm, c, col));
                EXPECT_GE(t, 0.0);
                EXPECT_LE(t, 1.0);
                EXPECT_LT(t, previous[c]) << "h " << h << " mu " << mu << " step " << i;
                previous[c] = t;
            }
        }
    }
    // transmittance_to_boundary: 0 for a ray that hits the ground when the ground blocks.
    for (double t : transmittance_to_boundary(atm, atm.bottom_radius_m + 1000.0, -0.5)) EXPECT_EQ(t, 0.0);
    for (double t : transmittance_to_boundary(atm, atm.bottom_radius_m + 1000.0, -0.5, false)) {
        EXPECT_GT(t, 0.0);
        EXPECT_LT(t, 1.0);
    }
}

// The reference path tracer's column table against the exact quadrature, on random rays of
// every preset at 48 wavelengths (see atmosphere/column_table.hpp for the two kinds of
// constituent and why the criteria differ for whole rays and segments).
TEST(ColumnTable, MatchesExactOpticalDepthOnRandomRays) {
    for (const std::string name : {"bruneton2017", "hazy", "polluted", "mars"}) {
        const Atmosphere atm = Atmosphere::preset(name, spectral_wavelengths_nm());
        const ColumnTable table(atm);
        const double R = atm.bottom_radius_m, top = atm.top_radius_m;
        double worst_top = 0.0, worst_segment = 0.0;
        PathRng rng(7, 0, 0);
        for (int n = 0; n < 3000; ++n) {
            // Altitudes biased low (u^3), cosines biased towards the horizon every third ray.
            const double h = (top - R) * std::pow(rng.uniform(), n % 2 ? 1.0 : 3.0);
            const double r = R + h;
            double mu = 2.0 * rng.uniform() - 1.0;
            if (n % 3 == 0) mu = 0.2 * std::pow(rng.uniform(), 3.0) * (rng.uniform() < 0.5 ? -1 : 1);
            // A segment of the ray, whether it hits the ground or not.
            const ColumnTable::Ray ray = table.ray(r, mu);
            const double s = ray.length() * rng.uniform();
            const ColumnDensity seg_exact = column_density(atm, r, mu, s), seg = ray.upto(s);
            // The whole ray to the top (flipped upwards if it would hit the ground).
            if (ray_hits_ground(r, mu, R)) mu = -mu;
            const ColumnDensity top_exact = column_density(atm, r, mu, distance_to_top(r, mu, top));
            const ColumnDensity to_top = table.to_top(r, mu);
            for (std::size_t c = 0; c < atm.channels(); ++c) {
                const double te = optical_depth(atm, c, top_exact);
                worst_top =
                    std::max(worst_top, std::abs(optical_depth(atm, c, to_top) - te) / (1e-5 * te + 1e-7));
                worst_segment = std::max(
                    worst_segment, std::abs(optical_depth(atm, c, seg) - optical_depth(atm, c, seg_exact)));
            }
        }
        std::printf(
            "[ column table ] %-12s to top: worst |dtau| / (1e-5 tau + 1e-7) = %.3f; "
            "segments: worst |dtau| = %.2e\n",
            name.c_str(), worst_top, worst_segment);
        EXPECT_LT(worst_top, 1.0) << name;
        EXPECT_LT(worst_segment, 1e-5) << name;
    }
}

TEST(ColumnTable, PiecewiseLinearLayersAreExact) {
    // A constant layer: the column is the path length inside it; the tent: 15 km
    // vertically. Both are integrated in closed form, so they match to rounding.
    Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    atm.rayleigh_density = DensityProfile({DensityLayer{0.0, 0.0, 0.0, 0.0, 1.0}});
    const ColumnTable table(atm);
    const double R = atm.bottom_radius_m, top = atm.top_radius_m;
    EXPECT_NEAR(table.to_top(R, 1.0).rayleigh_m, 60e3, 1e-6);
    EXPECT_NEAR(table.to_top(R, 1.0).absorption_m, 15e3, 1e-6);
    for (double mu : {0.0, 0.3, -0.2}) {
        const double r = R + 20e3;
        const ColumnTable::Ray ray = table.ray(r, mu);
        EXPECT_NEAR(ray.upto(ray.length()).rayleigh_m / ray.length(), 1.0, 1e-12);
        const double exact =
            density_integral(atm.absorption_density, R, r, mu, distance_to_boundary(r, mu, R, top));
        EXPECT_NEAR(ray.upto(ray.length()).absorption_m / exact, 1.0, 1e-9) << mu;
    }
}
