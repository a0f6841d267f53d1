// SPDX-License-Identifier: Apache-2.0
// Camera cloud passes (cloud_passes.hpp): closed forms for a constant slab in airless
// skies (opacity, radiance of single scattering, the transmittance-weighted depth in
// Blender's Z convention), geometry in front hiding the cloud, pixels without cloud, the
// air in front of the cloud (froxels against the per-pixel march), the composite's
// invariants, thread-count independence and cancellation.
#include <cmath>
#include <memory>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
using welkin::test::airless;
using welkin::test::HomogeneousBox;

namespace {

// A camera at the origin looking straight up (local -Z to world +Z: 180 degrees about X).
Camera camera_up(CameraType type) {
    Camera c;
    c.matrix_world = glm::dmat4(1.0);
    c.matrix_world[1][1] = -1.0;
    c.matrix_world[2][2] = -1.0;
    c.type = type;
    c.fov_rad = 40.0 * kDegree;
    c.ortho_scale = 100.0;
    return c;
}

SceneDescription scene_up(CameraType type, int w, int h, const Atmosphere& atm) {
    SceneDescription s;
    s.atmosphere = atm;
    s.camera = camera_up(type);
    s.resolution = {w, h, 100};
    s.sun_direction = {0.0, 0.0, 1.0};
    s.clouds = SceneClouds{};
    CloudLightingOptions& o = s.clouds->lighting;
    o.octaves = 1;  // single scattering: a closed form
    o.max_steps = 512;
    o.min_transmittance = 0.0;
    o.scattering.albedo = 1.0;
    return s;
}

// A horizontal slab bottom < z < bottom + H of sigma_t, wide enough for every ray here.
constexpr double kBottom = 1000.0, kH = 200.0, kSigma = 0.005;
HomogeneousBox slab() { return HomogeneousBox({-1e5, -1e5, kBottom}, {1e5, 1e5, kBottom + kH}, kSigma); }

// Transmittance-weighted distance into a homogeneous segment of length L, continuous form:
// int t sigma e^{-sigma t} dt / int sigma e^{-sigma t} dt over [0, L].
double weighted_depth(double sigma, double L) {
    const double e = std::exp(-sigma * L);
    return 1.0 / sigma - L * e / (1.0 - e);
}

}  // namespace

// Orthographic camera looking up through the slab, the sun at the zenith behind it
// (nu = 1 for every ray). Single scattering, no sky light, no air: along the ray the sun's
// optical depth and the view's add up to sigma H at every point, so
//     L = int_0^H sigma E p(1) e^{-sigma H} dz = sigma H e^{-sigma H} E p(1),
// alpha = 1 - e^{-sigma H}, and the depth is bottom + weighted_depth. Tolerances: alpha
// 1e-5 (the march is exact for a constant medium), radiance 0.5 % and depth 0.5 m (512
// steps of the energy-conserving march over 200 m, against the continuous integrals).
TEST(CloudPasses, ConstantSlabClosedForm) {
    const Atmosphere atm = airless();
    const SceneDescription s = scene_up(CameraType::Orthographic, 6, 4, atm);
    const HomogeneousBox box = slab();
    const CloudPasses p = render_cloud_passes(s, box);
    ASSERT_EQ(p.width, 6);
    ASSERT_EQ(p.height, 4);
    const double tau = kSigma * kH;
    const double p1 = CloudPhase{}(1.0);
    std::vector<float> spectrum(atm.channels());
    for (std::size_t c = 0; c < spectrum.size(); ++c)
        spectrum[c] = float(tau * std::exp(-tau) * atm.solar_irradiance[c] * p1);
    const std::array<double, 3> expected = SpectrumToRgb(atm.wavelengths_nm, -3.0).convert(spectrum);
    for (std::size_t q = 0; q < 24; ++q) {
        EXPECT_NEAR(p.clouds[q * 4 + 3], 1.0 - std::exp(-tau), 1e-5);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(p.clouds[q * 4 + c], expected[c], 5e-3 * expected[c]) << c;
        EXPECT_NEAR(p.depth[q], kBottom + weighted_depth(kSigma, kH), 0.5);
    }
}

// A perspective camera looking up: pixel rays at angle theta to the axis cross the slab
// over H / cos(theta); the pass holds the depth along the view axis, t cos(theta).
TEST(CloudPasses, DepthIsAlongTheViewAxis) {
    const SceneDescription s = scene_up(CameraType::Perspective, 8, 6, airless());
    const HomogeneousBox box = slab();
    const CloudPasses p = render_cloud_passes(s, box);
    const CameraRays rays(*s.camera, 8, 6);
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 8; ++i) {
            const CameraRays::Ray r = rays.at_pixel(i, j);
            const double cos_t = r.direction.z;
            const double t = kBottom / cos_t + weighted_depth(kSigma, kH / cos_t);
            const std::size_t q = std::size_t(j) * 8 + i;
            EXPECT_NEAR(p.depth[q], t * cos_t, 0.5) << i << ", " << j;
            EXPECT_NEAR(p.clouds[q * 4 + 3], 1.0 - std::exp(-kSigma * kH / cos_t), 1e-5);
        }
}

// Rays end at the geometry: a surface below the cloud hides it, one inside it cuts it.
// Pixels without cloud get alpha 0, no light and depth 1e10.
TEST(CloudPasses, GeometryInFrontHidesTheCloud) {
    const SceneDescription s = scene_up(CameraType::Orthographic, 4, 2, airless());
    const HomogeneousBox box = slab();
    // Row 0: surfaces at 500 m (in front), 1100 m (inside), sky (+inf), 1e10 (Cycles' sky).
    // Row 1: clear of the slab: nothing hides nothing.
    std::vector<float> depth{500.0f,  1100.0f, std::numeric_limits<float>::infinity(), 1e10f, 0.0f, 999.0f,
                             5000.0f, 1e9f};
    const CloudPasses p = render_cloud_passes(s, box, depth);
    const auto alpha = [&](int q) { return p.clouds[std::size_t(q) * 4 + 3]; };
    for (int q : {0, 4, 5}) {
        EXPECT_EQ(alpha(q), 0.0f) << q;
        EXPECT_EQ(p.depth[q], kNoCloudDepth) << q;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(p.clouds[std::size_t(q) * 4 + c], 0.0f) << q;
    }
    EXPECT_NEAR(alpha(1), 1.0 - std::exp(-kSigma * 100.0), 1e-5);
    EXPECT_NEAR(p.depth[1], kBottom + weighted_depth(kSigma, 100.0), 0.5);
    for (int q : {2, 3, 6, 7}) EXPECT_NEAR(alpha(q), 1.0 - std::exp(-kSigma * kH), 1e-5) << q;

    // A cloud only on one side of the screen: the other side is empty.
    const HomogeneousBox half({0.0, -1e5, kBottom}, {1e5, 1e5, kBottom + kH}, kSigma);
    const CloudPasses h = render_cloud_passes(s, half);
    for (int q = 0; q < 8; ++q) {
        // Orthographic rays start at x = -37.5 .. 37.5 m (ortho_scale 100 across 4 pixels).
        const bool inside = (q % 4) >= 2;
        EXPECT_EQ(h.clouds[std::size_t(q) * 4 + 3] > 0.0f, inside) << q;
        if (!inside) {
            EXPECT_EQ(h.depth[q], kNoCloudDepth);
        }
    }
    EXPECT_THROW(render_cloud_passes(s, box, std::vector<float>{1.0f}), InvalidArgument);
    std::vector<float> nan_depth(8, std::nanf(""));
    EXPECT_THROW(render_cloud_passes(s, box, nan_depth), InvalidArgument);
}

// The air in front of the cloud, hazy, a cloud box 15-25 km away seen near the horizon.
// The pass marches each pixel's air to its cloud depth; here that is checked against
// the froxel volume (32^3, fitted to those depths) sampled at the same depths, and for
// convergence. Tolerances as the aerial passes' own (test_aerial_perspective.cpp): median
// relative difference of Clouds.rgb under 1 %, 99th percentile under 5 %; doubling the
// march's steps moves the pass by under 0.5 % (99th percentile). The air is not negligible
// here: it changes most channels of most cloudy pixels by more than 10 %.
TEST(CloudPasses, AirInFrontMarchAgreesWithFroxels) {
    const int W = 64, H = 36;
    SceneDescription s = scene_up(CameraType::Perspective, W, H, Atmosphere::preset("hazy"));
    Camera& c = *s.camera;
    // Looking along +X, 5 degrees up.
    const double e = 5.0 * kDegree;
    const glm::dvec3 fwd(std::cos(e), 0.0, std::sin(e)), right(0.0, -1.0, 0.0);
    const glm::dvec3 up = glm::cross(right, fwd);
    c.matrix_world = glm::dmat4(1.0);
    c.matrix_world[0] = glm::dvec4(right, 0.0);
    c.matrix_world[1] = glm::dvec4(up, 0.0);
    c.matrix_world[2] = glm::dvec4(-fwd, 0.0);
    c.matrix_world[3] = glm::dvec4(0.0, 0.0, 10.0, 1.0);
    s.sun_direction = glm::normalize(glm::dvec3(0.3, 0.5, 0.4));
    s.clouds->lighting.octaves = 4;
    s.clouds->lighting.max_steps = 64;
    const HomogeneousBox box({15e3, -30e3, 1500.0}, {25e3, 30e3, 2500.0}, 0.002);
    const CloudPasses pass = render_cloud_passes(s, box);
    // The cloud's own light L_c: every cloud depth a "sky" depth for the air (T = 1, S = 0).
    SceneDescription bare_scene = s;
    bare_scene.aerial.sky_depth_m = 1.0;
    const CloudPasses bare = render_cloud_passes(bare_scene, box);
    // T and S of the froxel volume at the pass's cloud depths (1e10 where none: sky).
    const AerialPasses froxel = aerial_perspective_froxel(s.aerial_view(), pass.depth, W, H);
    SceneDescription fine = s;
    fine.aerial.raymarch_steps *= 2;
    const CloudPasses converged = render_cloud_passes(fine, box);
    std::vector<double> rel, conv;
    int hazed = 0, cloudy = 0;
    for (int q = 0; q < W * H; ++q) {
        const float a = pass.clouds[q * 4 + 3];
        EXPECT_EQ(bare.clouds[q * 4 + 3], a);
        if (a < 0.05f) continue;
        ++cloudy;
        for (int k = 0; k < 3; ++k) {
            const double v = pass.clouds[q * 4 + k];
            const double f =
                froxel.transmittance[q * 3 + k] * bare.clouds[q * 4 + k] + a * froxel.inscatter[q * 3 + k];
            rel.push_back(std::abs(f - v) / v);
            conv.push_back(std::abs(converged.clouds[q * 4 + k] - v) / v);
            if (std::abs(bare.clouds[q * 4 + k] - v) > 0.1 * v) ++hazed;
        }
    }
    ASSERT_GT(cloudy, W * H / 8);
    std::sort(rel.begin(), rel.end());
    std::sort(conv.begin(), conv.end());
    const double median = rel[rel.size() / 2], p99 = rel[rel.size() * 99 / 100];
    std::printf("cloud air: march vs froxel median %.3f %%, p99 %.3f %%; 2x steps p99 %.3f %%\n",
                100 * median, 100 * p99, 100 * conv[conv.size() * 99 / 100]);
    EXPECT_LT(median, 0.01);
    EXPECT_LT(p99, 0.05);
    EXPECT_LT(conv[conv.size() * 99 / 100], 0.005);
    EXPECT_GT(hazed, 3 * cloudy / 2);  // most of the 3 channels of the cloudy pixels
}

// A band of rows has exactly the whole frame's values in those rows.
TEST(CloudPasses, BandsHaveTheWholeFramesValues) {
    SceneDescription s = scene_up(CameraType::Perspective, 16, 12, Atmosphere::preset("clear"));
    s.clouds->lighting = CloudLightingOptions{};  // jittered: seeds must follow the frame
    const HomogeneousBox box({-300.0, -300.0, 1000.0}, {200.0, 250.0, 1300.0}, 0.01);
    std::vector<float> depth(16 * 12, 1e10f);
    for (int q = 0; q < 16 * 12; q += 5) depth[q] = 1100.0f;
    const CloudPasses whole = render_cloud_passes(s, box, depth);
    for (const RowRange rows : {RowRange{0, 5}, RowRange{5, 12}, RowRange{3, 4}}) {
        const CloudPasses band = render_cloud_passes(s, box, depth, nullptr, rows);
        ASSERT_EQ(band.height, rows.size());
        EXPECT_EQ(band.row_begin, rows.begin);
        const std::size_t q0 = std::size_t(rows.begin) * 16;
        for (std::size_t q = 0; q < band.depth.size(); ++q) {
            EXPECT_EQ(band.depth[q], whole.depth[q0 + q]);
            for (int k = 0; k < 4; ++k) EXPECT_EQ(band.clouds[q * 4 + k], whole.clouds[(q0 + q) * 4 + k]);
        }
    }
    EXPECT_THROW(render_cloud_passes(s, box, depth, nullptr, RowRange{5, 13}), InvalidArgument);
}

// The same with the upsampling (stride 4): a band is marched on the frame's lattice, widened
// to every block whose edge it touches, so it has the frame's values bit for bit, whether
// it starts on a lattice row or not, and wherever it ends (the frame's last block is 3
// rows). The cloud's edges and the geometry's speckles make blocks split.
TEST(CloudPasses, UpsampledBandsHaveTheWholeFramesValues) {
    const int W = 40, H = 31;
    SceneDescription s = scene_up(CameraType::Perspective, W, H, Atmosphere::preset("clear"));
    s.clouds->lighting = CloudLightingOptions{};
    s.clouds->upsampling.stride = 4;
    const HomogeneousBox box({-300.0, -300.0, 1000.0}, {200.0, 250.0, 1300.0}, 0.01);
    std::vector<float> depth(std::size_t(W) * H, 1e10f);
    for (int q = 0; q < W * H; q += 37) depth[q] = 1100.0f;
    const CloudPasses whole = render_cloud_passes(s, box, depth);
    s.clouds->upsampling.stride = 1;
    const CloudPasses every = render_cloud_passes(s, box, depth);
    s.clouds->upsampling.stride = 4;
    std::size_t differ = 0;
    for (std::size_t k = 0; k < whole.clouds.size(); ++k) differ += whole.clouds[k] != every.clouds[k];
    EXPECT_GT(differ, std::size_t(0));  // some pixels interpolated
    for (const RowRange rows : {RowRange{0, 5}, RowRange{4, 8}, RowRange{5, 12}, RowRange{3, 4},
                                RowRange{8, 9}, RowRange{27, 31}, RowRange{13, 29}}) {
        const CloudPasses band = render_cloud_passes(s, box, depth, nullptr, rows);
        ASSERT_EQ(band.height, rows.size());
        const std::size_t q0 = std::size_t(rows.begin) * W;
        for (std::size_t q = 0; q < band.depth.size(); ++q) {
            ASSERT_EQ(band.depth[q], whole.depth[q0 + q]) << rows.begin << " " << q;
            for (int k = 0; k < 4; ++k)
                ASSERT_EQ(band.clouds[q * 4 + k], whole.clouds[(q0 + q) * 4 + k]) << rows.begin << " " << q;
        }
    }
}

// The composite of the pass over a hazed render: an opaque cloud hides the render
// whatever it is; no cloud leaves the hazed render as it is; and the composite is linear
// in the render with slope (1 - alpha) x transmittance.
TEST(CloudPasses, CompositeInvariants) {
    SceneDescription s = scene_up(CameraType::Orthographic, 2, 2, Atmosphere::preset("hazy"));
    const HomogeneousBox thick({-1e5, -1e5, kBottom}, {0.0, 1e5, kBottom + kH}, 1.0);  // tau 200: opaque
    s.clouds->lighting.min_transmittance = 1e-3;
    const CloudPasses p = render_cloud_passes(s, thick);
    for (int q : {0, 2}) {  // x < 0: opaque
        const float a = p.clouds[q * 4 + 3];
        EXPECT_GT(a, 1.0f - 1e-3f);
        for (int k = 0; k < 3; ++k) {
            const float c = p.clouds[q * 4 + k];
            // The render (0 or 100, transmittance 0.9) shows through by at most 1e-3 of it.
            EXPECT_LT(composite_clouds(c, a, 100.0f, 0.9f, 0.1f) - composite_clouds(c, a, 0.0f, 0.9f, 0.1f),
                      1e-3f * 100.0f * 0.9f + 1e-4f);
            EXPECT_GT(c, 0.0f);
        }
    }
    for (int q : {1, 3}) {  // x > 0: no cloud
        EXPECT_EQ(p.clouds[q * 4 + 3], 0.0f);
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(composite_clouds(p.clouds[q * 4 + k], 0.0f, 7.0f, 0.5f, 0.25f), 7.0f * 0.5f + 0.25f);
    }
    EXPECT_FLOAT_EQ(
        composite_clouds(0.2f, 0.25f, 2.0f, 0.5f, 0.1f) - composite_clouds(0.2f, 0.25f, 1.0f, 0.5f, 0.1f),
        0.75f * 0.5f);
}

TEST(CloudPasses, SameAtOneAndTwoThreadsAndCancellable) {
    SceneDescription s = scene_up(CameraType::Perspective, 24, 16, Atmosphere::preset("clear"));
    s.clouds->lighting = CloudLightingOptions{};
    s.clouds->layers.push_back(CloudLayerParams{});
    s.clouds->layers[0].bottom_altitude_m = 800.0;
    s.clouds->layers[0].top_altitude_m = 1600.0;
    s.clouds->layers[0].coverage = 0.8;
    CloudPasses one, two;
    {
        tbb::global_control g(tbb::global_control::max_allowed_parallelism, 1);
        one = render_cloud_passes(s);
    }
    {
        tbb::global_control g(tbb::global_control::max_allowed_parallelism, 2);
        two = render_cloud_passes(s);
    }
    EXPECT_EQ(one.clouds, two.clouds);
    EXPECT_EQ(one.depth, two.depth);
    int cloudy = 0;
    for (std::size_t q = 0; q < one.depth.size(); ++q) {
        cloudy += one.clouds[q * 4 + 3] > 0.0f;
        for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isfinite(one.clouds[q * 4 + k]));
    }
    EXPECT_GT(cloudy, 0);

    struct Cancel final : Progress {
        bool report(double f) override { return f < 0.2; }
    } cancel;
    EXPECT_THROW(render_cloud_passes(s, {}, &cancel), Cancelled);

    // No clouds, no camera: errors naming them.
    SceneDescription clear = s;
    clear.clouds.reset();
    try {
        render_cloud_passes(clear);
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "clouds");
    }
    SceneDescription no_camera = s;
    no_camera.camera.reset();
    try {
        render_cloud_passes(no_camera);
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "camera");
    }
}
