// SPDX-License-Identifier: Apache-2.0
// The fast cloud march (clouds/lighting.hpp, defaults) against the path-tracing reference
// (clouds/reference.hpp, all orders) on three clouds: a thin wispy layer, a dense cumulus
// layer, and a VDB volume written here with OpenVDB. The same density, phase, albedo and
// light in both; the light is a constant sun and sky (the atmosphere's part is the same
// lookup in both methods and is tested with the LUTs).
//
// Figures printed per case: the error of the mean radiance over the views (bias), the mean
// absolute error per view relative to the mean radiance, and the largest transmittance
// difference. The tolerances are stated per case from what the approximation does
// (see the comment of each case), with the reference's own standard error added.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "welkin/base/math.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/noise.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/reference.hpp"
#include "welkin/clouds/vdb.hpp"

using namespace welkin;

namespace {

struct Comparison {
    double bias, mean_abs, max_dT, ref_se, dT_se;
};

// Views in a cone around `centre` (unit), a k x k grid of half-angle `half_angle`.
std::vector<glm::dvec3> view_grid(glm::dvec3 centre, double half_angle, int k) {
    centre = glm::normalize(centre);
    const glm::dvec3 a = glm::normalize(
        glm::cross(centre, std::abs(centre.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 b = glm::cross(centre, a);
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
            const double x = (2.0 * (i + 0.5) / k - 1.0) * std::tan(half_angle);
            const double y = (2.0 * (j + 0.5) / k - 1.0) * std::tan(half_angle);
            dirs.push_back(glm::normalize(centre + x * a + y * b));
        }
    return dirs;
}

Comparison compare(const char* name, const CloudDensity& density, const CloudIllumination& light,
                   glm::dvec3 eye, const std::vector<glm::dvec3>& dirs, int paths) {
    const auto t0 = std::chrono::steady_clock::now();
    const CloudResult fast = render_clouds(density, light, eye, dirs);
    const auto t1 = std::chrono::steady_clock::now();
    CloudReferenceOptions ro;
    ro.paths = paths;
    const CloudReferenceResult ref = render_clouds_reference(density, light, eye, dirs, ro);
    const auto t2 = std::chrono::steady_clock::now();
    const std::size_t nc = fast.channels;
    double sf = 0.0, sr = 0.0, sabs = 0.0, var = 0.0, max_dT = 0.0, max_dT_se = 0.0;
    for (std::size_t r = 0; r < dirs.size(); ++r) {
        const double lf = fast.radiance[r * nc + 1], lr = ref.radiance[r * nc + 1];
        sf += lf;
        sr += lr;
        sabs += std::abs(lf - lr);
        var += double(ref.radiance_error[r * nc + 1]) * ref.radiance_error[r * nc + 1];
        max_dT = std::max(max_dT, std::abs(double(fast.transmittance[r]) - ref.transmittance[r]));
        max_dT_se = std::max(max_dT_se, double(ref.transmittance_error[r]));
    }
    const double n = double(dirs.size());
    Comparison c{sf / sr - 1.0, sabs / sr, max_dT, std::sqrt(var) / n / (sr / n), max_dT_se};
    std::printf(
        "%-14s views %3zu  mean L: fast %.4g ref %.4g  bias %+6.1f %%  mean |err| %5.1f %%  max |dT| %.3f  "
        "ref se %.1f %%  truncated %.2g  time fast %.3f s ref %.2f s\n",
        name, dirs.size(), sf / n, sr / n, 100.0 * c.bias, 100.0 * c.mean_abs, c.max_dT, 100.0 * c.ref_se,
        ref.truncated_fraction, std::chrono::duration<double>(t1 - t0).count(),
        std::chrono::duration<double>(t2 - t1).count());
    return c;
}

// Sun 35 degrees up towards +x; a sky of 4 % of the sun's irradiance per steradian (about
// what the bruneton2017 sky's mean radiance is with the sun at that height).
// A dense cumulus layer (optical depth of tens) 1.5 to 2.7 km up, three quarters covered.
CloudLayerParams dense_cumulus() {
    CloudLayerParams p;
    p.bottom_altitude_m = 1500.0;
    p.top_altitude_m = 2700.0;
    p.coverage = 0.75;
    p.cloud_type = CloudType::cumulus;
    p.density_per_m = 0.03;
    return p;
}

ConstantIllumination test_daylight() {
    const double e = 35.0 * kDegree;
    return ConstantIllumination({std::cos(e), 0.0, std::sin(e)}, {1.0f, 1.0f, 1.0f}, {0.04f, 0.04f, 0.04f});
}

}  // namespace

// Thin, wispy stratocumulus (optical depth of order 1). Wrenninge's octaves alone add a
// fixed share (b + b^2 + b^3 = 0.875 of single scattering at tau -> 0) whatever the
// cloud's optical size, and came out too bright: +58 % (4096 paths, se 1.7 %). With the
// octaves weighted by the optical size along the sun line: bias +0.1 %, mean |error|
// 5.0 %. With the delta-Eddington slab (clouds/diffusion.hpp, the default) measured:
// bias -0.7 %, mean |error| 4.9 %; with its sides (the default since): -3.8 %, 5.3 %.
// Tolerance, the stated accuracy of the default march on such clouds: bias within
// +-10 %, mean |error| < 15 % (tightened from [-10 %, +70 %] and 70 %); transmittance
// within 0.01 + 4 se.
TEST(CloudFastVsReference, ThinWispyLayer) {
    CloudLayerParams p;
    p.bottom_altitude_m = 1500.0;
    p.top_altitude_m = 2300.0;
    p.coverage = 0.55;
    p.cloud_type = CloudType::stratocumulus;
    p.density_per_m = 0.004;
    p.detail_strength = 0.6;
    const ProceduralClouds layer(p);
    const Comparison c =
        compare("thin wispy", layer, test_daylight(), {0, 0, 0}, view_grid({0.3, 0.4, 1.0}, 0.5, 5), 4096);
    EXPECT_LT(std::abs(c.bias), 0.10 + 3.0 * c.ref_se);
    EXPECT_LT(c.mean_abs, 0.15 + 3.0 * c.ref_se);
    EXPECT_LT(c.max_dT, 0.01 + 4.0 * c.dT_se);
}

// Dense cumulus (optical depth of tens), seen from below. The light reaching the cloud's
// base has diffused through it, scattered tens of times. Wrenninge's octaves cannot carry
// it (their slowest term is exp(-tau / 8)): -48 % (256 paths, se 2.8 %). The
// delta-Eddington slab along the sun line (the default; its diffuse light falls off
// linearly with depth) measured: bias +7.3 %, mean |error| 13 %; with its sides (light
// leaking out of the cells across the sun line, the default since) -11.2 %, 17 %: the one
// chord the march measures overstates the leak of a wide, dense layer. (The sky light is exact
// here, albedo 1.) Tolerance, the stated accuracy on dense clouds seen from below: bias
// within +-20 %, mean |error| < 30 % (tightened from [-60 %, +10 %] and 60 %);
// transmittance within 0.01 + 4 se.
TEST(CloudFastVsReference, DenseCumulus) {
    const ProceduralClouds layer(dense_cumulus());
    const Comparison c =
        compare("dense cumulus", layer, test_daylight(), {0, 0, 0}, view_grid({0.3, 0.4, 1.0}, 0.5, 4), 256);
    EXPECT_LT(std::abs(c.bias), 0.20 + 3.0 * c.ref_se);
    EXPECT_LT(c.mean_abs, 0.30 + 3.0 * c.ref_se);
    EXPECT_LT(c.max_dT, 0.01 + 4.0 * c.dT_se);
}

// The dense cumulus under two skies: the sky above the horizon 6 % of the sun's irradiance
// per steradian, the ground below 1.5 % (a quarter: the add-on's world seen from the
// ground, docs/validation.md "The light from below"), sun off so that the sky light alone
// is compared, views from below at the bases. The reference takes the hemisphere each path
// leaves into; the march, Eddington's slab between the two skies (lighting.hpp, "Sky
// light"). Measured: docs/validation.md, "The light from below"; the sphere's mean (what
// lit clouds before) would light the bases with 2.5 times the light from below.
// Tolerance: bias within +-10 %, mean |error| < 15 %; transmittance within 0.01 + 4 se.
TEST(CloudFastVsReference, DenseCumulusUnderTwoSkies) {
    const ProceduralClouds layer(dense_cumulus());
    const double e = 35.0 * kDegree;
    const ConstantIllumination two_skies({std::cos(e), 0.0, std::sin(e)}, {0.0f, 0.0f, 0.0f},
                                         {0.06f, 0.06f, 0.06f}, {0.015f, 0.015f, 0.015f});
    const Comparison c =
        compare("two skies", layer, two_skies, {0, 0, 0}, view_grid({0.3, 0.4, 1.0}, 0.5, 4), 256);
    EXPECT_LT(std::abs(c.bias), 0.10 + 3.0 * c.ref_se);
    EXPECT_LT(c.mean_abs, 0.15 + 3.0 * c.ref_se);
    EXPECT_LT(c.max_dT, 0.01 + 4.0 * c.dT_se);
}

// A VDB cloud: a ball of 400 m with Worley-noise structure, written by this test, placed
// by a Blender-style object matrix; optical depth ~5 across, views from below and to the
// side. With the octaves (weighted by the optical size): bias -8.2 %, mean |error| 22 %
// (1024 paths, se 1.6 %), the core too dark as in the dense case. With the
// delta-Eddington slab without sides: bias +10.8 %, mean |error| 14 %, too bright (light
// could not leave by the sides); with its sides (the default) -5.2 %, 11.5 %.
// Tolerance: bias within +-15 %, mean |error| < 25 % (from 35 %);
// transmittance within 0.01 + 4 se.
TEST(CloudFastVsReference, VdbVolume) {
    test::TempDir dir;
    const std::string path = dir.file("cloud.vdb");
    test::write_vdb(path, {test::make_float_grid("density", 10.0, 21, [](int i, int j, int k) {
                        const double r = std::sqrt(double(i * i + j * j + k * k)) / 20.0;
                        if (r >= 1.0) return 0.0f;
                        const double w =
                            tileable_worley((i + 21) / 42.0, (j + 21) / 42.0, (k + 21) / 42.0, 4, 3);
                        return float((1.0 - r * r) * (0.3 + 0.7 * w));
                    })});
    VdbCloudOptions o;
    o.matrix_world = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 1500.0, 900.0));
    o.density_scale = 0.03;
    const VdbClouds vdb(path, o);
    const Comparison c =
        compare("vdb", vdb, test_daylight(), {0, 0, 0}, view_grid({0.0, 1500.0, 900.0}, 0.12, 5), 1024);
    EXPECT_LT(std::abs(c.bias), 0.15 + 3.0 * c.ref_se);
    EXPECT_LT(c.mean_abs, 0.25 + 3.0 * c.ref_se);
    EXPECT_LT(c.max_dT, 0.01 + 4.0 * c.dT_se);
}
