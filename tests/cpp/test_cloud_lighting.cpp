// SPDX-License-Identifier: Apache-2.0
// Cloud lighting: the fast march and the path-tracing reference against closed forms, and
// the fast march against the reference on three clouds (a thin wispy layer, a dense
// cumulus layer, a VDB written here), with the tolerance stated per case.
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "welkin/base/math.hpp"
#include "welkin/base/rng.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/reference.hpp"
#include "welkin/clouds/vdb.hpp"

using namespace welkin;
using welkin::test::HomogeneousBox;

TEST(CloudPhase, NormalisedAndSampledMeanCosine) {
    const CloudPhase p;
    // Integral over the sphere, 2 pi int_{-1}^{1} p(nu) dnu, by a fine midpoint rule.
    const int n = 200000;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += p(-1.0 + (i + 0.5) * 2.0 / n) * 2.0 / n;
    EXPECT_NEAR(kTwoPi * sum, 1.0, 1e-4);
    // Sampled directions: mean cosine about d equals w g_f + (1 - w) g_b.
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
    double m = 0.0, m2 = 0.0;
    const int k = 200000;
    for (int i = 0; i < k; ++i) {
        PathRng rng(9, 0, std::uint64_t(i));
        const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        const double c = glm::dot(d, p.sample(d, u0, u1, u2));
        m += c;
        m2 += c * c;
    }
    m /= k;
    const double se = std::sqrt((m2 / k - m * m) / k);
    EXPECT_NEAR(m, p.mean_cosine(), 4.0 * se);
}

namespace {

ConstantIllumination sun_only(glm::dvec3 s, float e) {
    return ConstantIllumination(s, {e, e, e}, {0.0f, 0.0f, 0.0f});
}

}  // namespace

// T = exp(-tau) through a homogeneous box: exactly for the march (a constant density is
// integrated exactly step by step), within 4 standard errors for ratio tracking.
TEST(CloudClosedForm, TransmittanceOfHomogeneousBox) {
    const HomogeneousBox box({0, -50, -50}, {100, 50, 50}, 0.015);  // tau = 1.5 along x
    const auto light = sun_only({0, 0, 1}, 1.0f);
    const std::vector<glm::dvec3> dirs = {{1, 0, 0}};
    const CloudResult fast = render_clouds(box, light, {-10, 0, 0}, dirs);
    EXPECT_NEAR(fast.transmittance[0], std::exp(-1.5), 1e-5);
    CloudReferenceOptions ro;
    ro.paths = 4000;
    const CloudReferenceResult ref = render_clouds_reference(box, light, {-10, 0, 0}, dirs, ro);
    EXPECT_NEAR(ref.transmittance[0], std::exp(-1.5), 4.0 * ref.transmittance_error[0] + 1e-6);
    EXPECT_GT(ref.transmittance_error[0], 0.0f);
    // Depth: the mean distance to the first collision within the box, conditioned on one:
    // 10 + 1/sigma - D e^{-tau} / (1 - e^{-tau}).
    const double expected_depth = 10.0 + 1.0 / 0.015 - 100.0 * std::exp(-1.5) / (1.0 - std::exp(-1.5));
    EXPECT_NEAR(fast.depth_m[0], expected_depth, 0.5);
    EXPECT_NEAR(ref.depth_m[0], expected_depth, 2.0);  // 4000 paths: the sd is ~30 m / sqrt(3100)
}

namespace {

// A homogeneous box far along one long majorant segment [0, length] (a layer's shell seen
// low over the horizon), with the feature size `feature`.
class FarBox final : public CloudDensity {
public:
    FarBox(glm::dvec3 lo, glm::dvec3 hi, double sigma_t, double length, double feature)
        : box_(lo, hi, sigma_t), length_(length), feature_(feature) {}
    double sigma_t(const glm::dvec3& p) const override { return box_.sigma_t(p); }
    void segments(const CloudRay&, double t_max, std::vector<MajorantSegment>& out) const override {
        out.assign(1, {0.0, std::min(length_, t_max), 1.0});
    }
    double feature_size_m() const override { return feature_; }

private:
    HomogeneousBox box_;
    double length_, feature_;
};

}  // namespace

// The surface cut (lighting.hpp, "The surface"): 20 km of segment in 96 steps of 208 m
// through a box 400 m deep, tau = 2. Marched at the base step alone, a ray holds one or two
// samples of the box, tau 1.04 or 2.08, as its jitter falls: a cloud's outline turns to
// speckle. Cut where the cloud is (pieces of 26 m: the base step over 8), each face falls
// within a piece, so every ray's depth is within 2 sigma 26 m = 0.26 of the truth, and
// their mean (the jitter uniform) within 0.02.
TEST(CloudSteps, SurfaceCutKeepsAFarCloudsDepth) {
    const double sigma = 0.005, depth = 400.0;
    const FarBox box({10050, -1e4, -1e4}, {10050 + depth, 1e4, 1e4}, sigma, 20000.0, 10.0);
    const auto light = sun_only({0, 0, 1}, 1.0f);
    const std::vector<glm::dvec3> dirs(256, glm::dvec3(1, 0, 0));
    const auto worst_and_mean = [&](int cut) {
        CloudLightingOptions o;
        o.surface_cut = cut;
        const CloudResult r = render_clouds(box, light, glm::dvec3(0.0), dirs, o);
        double worst = 0.0, mean = 0.0;
        for (float t : r.transmittance) {
            const double tau = -std::log(double(t));
            worst = std::max(worst, std::abs(tau - sigma * depth));
            mean += tau / double(dirs.size());
        }
        return std::pair{worst, mean};
    };
    const auto [worst_cut, mean_cut] = worst_and_mean(8);
    const auto [worst_base, mean_base] = worst_and_mean(1);
    std::printf("tau error per ray, worst: cut %.3f, base step alone %.3f; mean tau %.3f, %.3f (exact 2)\n",
                worst_cut, worst_base, mean_cut, mean_base);
    EXPECT_LE(worst_cut, 2.0 * sigma * (20000.0 / 96.0 / 8.0) + 1e-9);
    EXPECT_NEAR(mean_cut, sigma * depth, 0.02);
    EXPECT_GT(worst_base, 0.9);  // what the cut mends: one sample of the box missed
}

// A bad ray is refused naming it, whichever ray of the frame it is.
TEST(CloudSteps, BadRaysAreRefusedByName) {
    const HomogeneousBox box({0, -50, -50}, {100, 50, 50}, 0.015);
    const auto light = sun_only({0, 0, 1}, 1.0f);
    const std::vector<glm::dvec3> dirs(3, glm::dvec3(1, 0, 0));
    const auto refused = [&](std::vector<glm::dvec3> origins, std::vector<double> lengths) {
        try {
            render_clouds(box, light, origins, dirs, lengths);
        } catch (const InvalidArgument& e) {
            return e.parameter();
        }
        return std::string("accepted");
    };
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(refused({{-10, 0, 0}, {-10, 0, 0}, {-10, 0, nan}}, {}), "origins[2][2]");
    EXPECT_EQ(refused({{-10, 0, 0}, {-10, std::numeric_limits<double>::infinity(), 0}, {-10, 0, 0}}, {}),
              "origins[1][1]");
    EXPECT_EQ(refused({{-10, 0, 0}}, {50.0, -1.0, 50.0}), "max_distances[1]");
    EXPECT_EQ(refused({{-10, 0, 0}}, {50.0, 50.0, 50.0}), "accepted");
}

// Single scattering of a homogeneous slab, sun overhead, view horizontal through it: every
// point of the view ray sees the sun through the same depth l to the top, so
//   L_1 = albedo p(0) E exp(-sigma l) (1 - exp(-sigma D)).
// The march with one octave and no sky is single scattering; the reference cut at one
// bounce is too.
TEST(CloudClosedForm, SingleScatteringOfThinSlab) {
    const double sigma = 0.002, D = 200.0, l = 30.0;
    const HomogeneousBox slab({0, -1e5, -100}, {D, 1e5, l}, sigma);  // top at z = l
    const auto light = sun_only({0, 0, 1}, 2.0f);
    const std::vector<glm::dvec3> dirs = {{1, 0, 0}};
    CloudScattering sc;
    sc.albedo = 0.9;
    const double expected =
        sc.albedo * sc.phase(0.0) * 2.0 * std::exp(-sigma * l) * (1.0 - std::exp(-sigma * D));
    CloudLightingOptions o;
    o.scattering = sc;
    o.octaves = 1;
    o.ambient_steps = 0;
    const CloudResult fast = render_clouds(slab, light, {-5, 0, 0}, dirs, o);
    EXPECT_NEAR(fast.radiance[0] / expected, 1.0, 1e-4);
    CloudReferenceOptions ro;
    ro.scattering = sc;
    ro.max_bounces = 1;
    ro.paths = 20000;
    const CloudReferenceResult ref = render_clouds_reference(slab, light, {-5, 0, 0}, dirs, ro);
    EXPECT_NEAR(ref.radiance[0], expected, 4.0 * ref.radiance_error[0]);
    std::printf("single scattering: analytic %.6g, march %.6g, reference %.6g +- %.2g\n", expected,
                fast.radiance[0], ref.radiance[0], ref.radiance_error[0]);
}

// In a uniform isotropic radiance field L, a conservative medium (albedo 1) changes
// nothing: the uniform field solves the transfer equation (in-scattering sigma_s L equals
// extinction sigma_t L). So what a cloud adds is exactly (1 - T) L, at all orders; with
// albedo < 1 it is less. The reference must reproduce that; no method may create energy:
// the march's in-scattering is bounded by (1 - T) L for any albedo.
TEST(CloudClosedForm, UniformSkyIsInvariantAndEnergyIsNeverCreated) {
    const HomogeneousBox cube({-50, -50, -50}, {50, 50, 50}, 0.03);  // tau = 3 across
    const ConstantIllumination sky({0, 0, 1}, {0.0f, 0.0f, 0.0f}, {1.0f, 0.5f, 0.25f});
    const glm::dvec3 eye(-200, 0, 0);
    const std::vector<glm::dvec3> aimed = {
        {1, 0, 0}, glm::normalize(glm::dvec3(200, 20, 10)), glm::normalize(glm::dvec3(200, 0, 40))};
    CloudReferenceOptions ro;
    ro.paths = 1500;
    const CloudReferenceResult ref = render_clouds_reference(cube, sky, eye, aimed, ro);
    EXPECT_EQ(ref.truncated_fraction, 0.0);
    for (std::size_t r = 0; r < aimed.size(); ++r)
        for (std::size_t c = 0; c < 3; ++c) {
            const double L = std::array<double, 3>{1.0, 0.5, 0.25}[c];
            const double expected = (1.0 - ref.transmittance[r]) * L;
            EXPECT_NEAR(ref.radiance[r * 3 + c], expected,
                        4.0 * ref.radiance_error[r * 3 + c] + 4.0 * ref.transmittance_error[r] * L);
        }
    for (double albedo : {1.0, 0.6}) {
        CloudLightingOptions o;
        o.scattering.albedo = albedo;
        const CloudResult fast = render_clouds(cube, sky, eye, aimed, o);
        for (std::size_t r = 0; r < aimed.size(); ++r) {
            EXPECT_LE(fast.radiance[r * 3], (1.0 - fast.transmittance[r]) * 1.0 + 1e-6);
            if (albedo == 1.0) {
                EXPECT_NEAR(fast.radiance[r * 3], 1.0 - fast.transmittance[r], 1e-5);
            }
            std::printf("uniform sky, albedo %.1f, view %zu: march adds %.4f of (1 - T) L (exact: %s)\n",
                        albedo, r, fast.radiance[r * 3] / (1.0 - fast.transmittance[r]),
                        albedo == 1.0 ? "1" : "< 1");
        }
    }
    CloudReferenceOptions ra = ro;
    ra.scattering.albedo = 0.6;
    const CloudReferenceResult absorbing = render_clouds_reference(cube, sky, eye, aimed, ra);
    for (std::size_t r = 0; r < aimed.size(); ++r)
        EXPECT_LT(absorbing.radiance[r * 3],
                  (1.0 - absorbing.transmittance[r]) - 4.0 * absorbing.radiance_error[r * 3]);
}

// Two skies: a homogeneous slab (500 m thick, vertical optical depth 16, 20 km wide),
// albedo 1, under a sky of radiance 1 above the horizon and 0 below. The slab is the same
// turned upside down, and under L above and below the field is L everywhere (the test
// above); by linearity the radiance leaving the top upwards (r, the sky reflected) and the
// radiance leaving the base downwards at the same angle (t, the sky let through) add up to
// exactly 1. The reference must find that. The march's Eddington mix (lighting.hpp, "Sky
// light") must come within 3 % of the reference at the top and 10 % at the base (measured:
// -1.4 / -1.1 % and +5.8 / +6.6 %, vertical / 60 deg; the reference's standard error is
// 0.7 / 3 % of them; the mean field J alone, without the flux term, was +7.5 / -32 %). The
// sphere's mean, what lit clouds before the two skies, gives 0.5 at both faces. A sky the same above and
// below goes through the one-sky path: the sums of its two halves' renders must equal it (the mix's weights
// sum to 1).
TEST(CloudClosedForm, TwoSkiesSlabReflectsAndTransmitsAllOfIt) {
    const HomogeneousBox slab({-1e4, -1e4, -250}, {1e4, 1e4, 250}, 16.0 / 500.0);
    const ConstantIllumination above_only({0, 0, 1}, {0.0f}, {1.0f}, {0.0f});
    const glm::dvec3 top_eye(0, 0, 1000), base_eye(0, 0, -1000);
    const double c60 = std::cos(kPi / 3), s60 = std::sin(kPi / 3);
    const std::vector<glm::dvec3> down = {{0, 0, -1}, {s60, 0, -c60}}, up = {{0, 0, 1}, {s60, 0, c60}};
    CloudReferenceOptions ro;
    ro.paths = 4000;
    const CloudReferenceResult r = render_clouds_reference(slab, above_only, top_eye, down, ro);
    const CloudReferenceResult t = render_clouds_reference(slab, above_only, base_eye, up, ro);
    CloudLightingOptions o;
    o.shadow_grid_spacing_m = 25.0;
    const CloudResult fr = render_clouds(slab, above_only, top_eye, down, o);
    const CloudResult ft = render_clouds(slab, above_only, base_eye, up, o);
    for (std::size_t k = 0; k < down.size(); ++k) {
        EXPECT_LT(r.truncated_fraction + t.truncated_fraction, 1e-3);
        EXPECT_NEAR(r.radiance[k] + t.radiance[k], 1.0,
                    4.0 * std::hypot(r.radiance_error[k], t.radiance_error[k]));
        std::printf(
            "two skies, view %s: reference top %.4f +- %.4f base %.4f +- %.4f (sum %.4f); "
            "march top %.4f (%+.1f %%) base %.4f (%+.1f %%)\n",
            k == 0 ? "vertical" : "60 deg", r.radiance[k], r.radiance_error[k], t.radiance[k],
            t.radiance_error[k], r.radiance[k] + t.radiance[k], fr.radiance[k],
            100.0 * (fr.radiance[k] / r.radiance[k] - 1.0), ft.radiance[k],
            100.0 * (ft.radiance[k] / t.radiance[k] - 1.0));
        EXPECT_NEAR(fr.radiance[k], r.radiance[k], 0.03 * r.radiance[k]);
        EXPECT_NEAR(ft.radiance[k], t.radiance[k], 0.10 * t.radiance[k]);
    }
    // The mix's weights sum to 1: sky above plus sky below is the one-sky render.
    const ConstantIllumination both({0, 0, 1}, {0.0f}, {1.0f}), below_only({0, 0, 1}, {0.0f}, {0.0f}, {1.0f});
    for (const glm::dvec3& eye : {top_eye, base_eye}) {
        const auto& dirs = eye.z > 0 ? down : up;
        const CloudResult a = render_clouds(slab, above_only, eye, dirs, o);
        const CloudResult b = render_clouds(slab, below_only, eye, dirs, o);
        const CloudResult ab = render_clouds(slab, both, eye, dirs, o);
        for (std::size_t k = 0; k < dirs.size(); ++k)
            EXPECT_NEAR(a.radiance[k] + b.radiance[k], ab.radiance[k], 1e-5);
    }
}
