// SPDX-License-Identifier: Apache-2.0
// Aerial perspective: closed forms (no air, exact optical depth along a horizontal ray),
// invariants (monotone in depth, sky pixels), bad input, and the froxel volume against the
// per-pixel ray march with stated tolerances in strong haze out to 80 km.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "aerial_comparison.hpp"
#include "invalid_argument_testing.hpp"
#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/base/memory.hpp"
#include "welkin/color/color.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
using welkin::test::parameter_of;

namespace {

// Camera at (0, 0, height) looking along world +X (Blender rotation (90, 0, -90) degrees),
// tilted down by `pitch_rad`.
Camera camera_along_x(double height_m, double pitch_rad = 0.0) {
    const double c = std::cos(pitch_rad), s = std::sin(pitch_rad);
    const glm::dvec3 forward{c, 0.0, -s}, up{s, 0.0, c}, right{0.0, -1.0, 0.0};
    Camera cam;
    cam.matrix_world = glm::dmat4(glm::dvec4(right, 0), glm::dvec4(up, 0), glm::dvec4(-forward, 0),
                                  glm::dvec4(0, 0, height_m, 1));
    cam.clip_end_m = 1e6;
    return cam;
}

SceneDescription scene_for(const std::string& preset, const Camera& cam, int width, int height,
                           double sun_elevation_deg, double sun_azimuth_deg) {
    SceneDescription s;
    s.atmosphere = Atmosphere::preset(preset);
    s.camera = cam;
    s.resolution = {width, height, 100};
    s.sun_direction = sun_direction_from_angles_deg(sun_elevation_deg, sun_azimuth_deg);
    return s;
}

}  // namespace

TEST(AerialPerspective, NoAirGivesFullTransmittanceAndNoInscatter) {
    SceneDescription s = scene_for("bruneton2017", camera_along_x(100.0, 0.05), 24, 16, 20.0, 0.0);
    Atmosphere& a = s.atmosphere;
    std::fill(a.rayleigh_scattering.begin(), a.rayleigh_scattering.end(), 0.0);
    std::fill(a.mie_scattering.begin(), a.mie_scattering.end(), 0.0);
    std::fill(a.mie_extinction.begin(), a.mie_extinction.end(), 0.0);
    std::fill(a.absorption_extinction.begin(), a.absorption_extinction.end(), 0.0);
    std::vector<float> depth(24 * 16);
    for (std::size_t k = 0; k < depth.size(); ++k) depth[k] = float(10.0 + 3000.0 * double(k));
    for (const auto method : {AerialOptions::Method::Froxel, AerialOptions::Method::Raymarch}) {
        s.aerial.method = method;
        const AerialPasses p = aerial_perspective(s.aerial_view(), depth, 24, 16);
        for (std::size_t k = 0; k < p.inscatter.size(); ++k) {
            EXPECT_EQ(p.inscatter[k], 0.0f) << k;
            EXPECT_EQ(p.transmittance[k], 1.0f) << k;
        }
    }
}

// A horizontal ray from 1 km up, 20 km long: T against the exact optical depth
// (optical_depth.hpp, Gauss-Legendre to ~1e-9), taken to RGB by the documented
// sunlit-surface ratio. Tolerance: 2e-4 absolute for the march (midpoint rule on 64 steps
// of an almost constant density: altitude changes by 31 m over the ray), 1e-3 for the
// froxels (the same integral in 4 sub-steps per slice, read at the last slice).
TEST(AerialPerspective, TransmittanceMatchesExactOpticalDepthAlongAHorizontalRay) {
    const int W = 33, H = 33;  // odd: the centre pixel looks exactly along the axis
    for (const char* preset : {"bruneton2017", "polluted"}) {
        SceneDescription s = scene_for(preset, camera_along_x(1000.0), W, H, 30.0, 90.0);
        const double d = 20e3;
        std::vector<float> depth(W * H, float(d));
        const Atmosphere& atm = s.atmosphere;
        const double r = atm.bottom_radius_m + 1000.0;
        const ColumnDensity col = column_density(atm, r, 0.0, d);
        std::vector<float> E_T(atm.channels());
        std::vector<float> E(atm.channels());
        for (std::size_t c = 0; c < atm.channels(); ++c) {
            E[c] = float(atm.solar_irradiance[c]);
            E_T[c] = float(atm.solar_irradiance[c] * std::exp(-optical_depth(atm, c, col)));
        }
        const SpectrumToRgb sun(atm.wavelengths_nm, 0.0);
        const std::array<double, 3> num = sun.convert(E_T), den = sun.convert(E);
        for (const auto method : {AerialOptions::Method::Raymarch, AerialOptions::Method::Froxel}) {
            s.aerial.method = method;
            const AerialPasses p = aerial_perspective(s.aerial_view(), depth, W, H);
            const std::size_t centre = (std::size_t(H / 2) * W + W / 2) * 3;
            const double tol = method == AerialOptions::Method::Raymarch ? 2e-4 : 1e-3;
            for (int k = 0; k < 3; ++k) {
                const double expected = num[k] / den[k];
                EXPECT_NEAR(p.transmittance[centre + k], expected, tol) << preset << " channel " << k;
                EXPECT_GT(p.inscatter[centre + k], 0.0f);
            }
        }
    }
}

// Along one direction (an orthographic camera: every pixel's ray is parallel), deeper
// pixels see less transmittance and more in-scattering. The exact integral is monotone
// per wavelength; in RGB, whose conversion matrix has negative entries, the invariant is
// the luminance Y (non-negative weights) and the transmittance channels. Slack: float
// rounding for the froxels (2e-6 relative: they interpolate monotone slices). The march
// gives each pixel its own steps, whose discretisation error (1e-4 relative with 64 steps
// here, once the haze saturates and L barely grows) differs from pixel to pixel; with
// 1024 steps it is 256 times smaller, and the slack is 1e-5.
TEST(AerialPerspective, MonotoneInDepth) {
    Camera cam = camera_along_x(300.0, 0.02);
    cam.type = CameraType::Orthographic;
    cam.ortho_scale = 1e-3;
    const int W = 200, H = 2;
    SceneDescription s = scene_for("hazy", cam, W, H, 8.0, 20.0);
    // At 680/550/440 nm, whose RGB conversion (Bruneton's) keeps each transmittance channel a
    // non-negative mix of the wavelengths' own; the default four wavelengths' fitted
    // conversion has negative weights, under which an RGB channel of T may rise by a few
    // 1e-6 while every wavelength's T falls.
    s.atmosphere = Atmosphere::preset("hazy", test::kPeerWavelengthsNm);
    std::vector<float> depth(W * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) depth[y * W + x] = float(5.0 * std::pow(1.05, x));  // 5 m .. 80 km
    const auto Y = [](const float* rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; };
    for (const auto method : {AerialOptions::Method::Froxel, AerialOptions::Method::Raymarch}) {
        s.aerial.method = method;
        const double slack = method == AerialOptions::Method::Froxel ? 2e-6 : 1e-5;
        s.aerial.raymarch_steps = 1024;
        const AerialPasses p = aerial_perspective(s.aerial_view(), depth, W, H);
        for (int x = 1; x < W; ++x) {
            for (int c = 0; c < 3; ++c)
                EXPECT_LE(p.transmittance[x * 3 + c], p.transmittance[(x - 1) * 3 + c] * (1 + slack)) << x;
            const double y1 = Y(&p.inscatter[x * 3]), y0 = Y(&p.inscatter[(x - 1) * 3]);
            EXPECT_GE(y1, y0 * (1 - slack)) << "pixel " << x << " method " << aerial_method_name(method);
        }
        EXPECT_GT(Y(&p.inscatter[(W - 1) * 3]), 100.0 * Y(&p.inscatter[0]));
        EXPECT_LT(p.transmittance[(W - 1) * 3 + 2], 0.1f);  // 80 km of haze: nearly opaque
    }
}

TEST(AerialPerspective, SkyPixelsAreLeftToTheSky) {
    SceneDescription s = scene_for("hazy", camera_along_x(100.0), 8, 4, 20.0, 0.0);
    std::vector<float> depth(32, 5000.0f);
    depth[3] = std::numeric_limits<float>::infinity();
    depth[4] = 1e10f;  // Cycles' background depth
    depth[5] = 0.0f;
    for (const auto method : {AerialOptions::Method::Froxel, AerialOptions::Method::Raymarch}) {
        s.aerial.method = method;
        const AerialPasses p = aerial_perspective(s.aerial_view(), depth, 8, 4);
        for (int k : {3, 4, 5})
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(p.transmittance[k * 3 + c], 1.0f);
                EXPECT_EQ(p.inscatter[k * 3 + c], 0.0f);
            }
        EXPECT_LT(p.transmittance[0], 1.0f);
    }
    // All sky: nothing to fit the volume to, still T = 1, L = 0.
    std::vector<float> sky(32, std::numeric_limits<float>::infinity());
    s.aerial.method = AerialOptions::Method::Froxel;
    const AerialPasses p = aerial_perspective(s.aerial_view(), sky, 8, 4);
    EXPECT_EQ(*std::min_element(p.transmittance.begin(), p.transmittance.end()), 1.0f);
    EXPECT_EQ(*std::max_element(p.inscatter.begin(), p.inscatter.end()), 0.0f);
}

TEST(AerialPerspective, BadInputNamesTheParameter) {
    SceneDescription s = scene_for("clear", camera_along_x(100.0), 8, 4, 20.0, 0.0);
    std::vector<float> depth(32, 100.0f);
    std::vector<float> bad = depth;
    bad[9] = std::nanf("");
    EXPECT_EQ(parameter_of([&] { aerial_perspective(s.aerial_view(), bad, 8, 4); }), "depth");
    bad[9] = -1.0f;
    EXPECT_EQ(parameter_of([&] { aerial_perspective(s.aerial_view(), bad, 8, 4); }), "depth");
    bad[9] = -std::numeric_limits<float>::infinity();
    EXPECT_EQ(parameter_of([&] { aerial_perspective(s.aerial_view(), bad, 8, 4); }), "depth");
    EXPECT_EQ(parameter_of([&] { aerial_perspective(s.aerial_view(), depth, 4, 8); }),
              "depth");  // wrong size
    EXPECT_EQ(parameter_of([&] {
                  aerial_perspective(s.aerial_view(), std::span<const float>(depth).first(31), 8, 4);
              }),
              "depth");
    SceneDescription huge = s;
    huge.resolution = {65536, 65536, 32767};
    EXPECT_EQ(parameter_of([&] {
                  check_frame_memory(huge.resolution.width(), huge.resolution.height(),
                                     kAerialPassBytesPerPixel, "passes");
              }),
              "resolution");
    SceneDescription none = s;
    none.camera.reset();
    EXPECT_EQ(parameter_of([&] { aerial_perspective(none.aerial_view(), depth, 8, 4); }), "camera");
    // The message names the pixel.
    bad[9] = std::nanf("");
    try {
        aerial_perspective(s.aerial_view(), bad, 8, 4);
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("x 1, y 1"), std::string::npos) << e.what();
    }
}

namespace {

// A synthetic depth buffer of a low camera over rolling terrain: ground intersected by each
// ray (flat plane at z = 0 seen from `height_m`, plus a ridge of "mountains" out to 80 km),
// sky above the horizon, and near objects in the lower left (a block at 30-60 m).
std::vector<float> terrain_depth(const SceneDescription& s, int W, int H, double height_m) {
    const CameraRays rays(*s.camera, W, H);
    std::vector<float> depth(std::size_t(W) * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const CameraRays::Ray r = rays.at_pixel(x, y);
            double t;
            const double ridge = 60e3 + 20e3 * std::sin(6.0 * double(x) / W);  // 40 - 80 km
            const double ridge_top = 1500.0 + 600.0 * std::cos(11.0 * double(x) / W);
            if (r.direction.z < 0.0 && (t = height_m / -r.direction.z) < ridge / r.direction.x) {
                // The plane, until it reaches the ridge.
            } else {
                t = ridge / r.direction.x;
                if (height_m + t * r.direction.z > ridge_top) t = std::numeric_limits<double>::infinity();
            }
            if (x < W / 5 && y > 2 * H / 3)
                t = (30.0 + 30.0 * double(y - 2 * H / 3) / H) * r.distance_per_depth;
            depth[std::size_t(y) * W + x] = float(t / r.distance_per_depth);  // the Z pass: along the axis
        }
    return depth;
}

using Comparison = test::AerialComparison;

Comparison compare(const AerialPasses& f, const AerialPasses& r, const std::vector<float>& depth) {
    return test::compare_aerial_passes(f, r, depth);
}

}  // namespace

// The froxel volume (32 x 32 x 32, depth fitted to the buffer: 80 km) against every
// pixel marched to its depth, in the hazy and polluted presets, the sun low in front of
// the camera (the Mie peak across the screen) and behind it. Tolerances, stated: median
// relative in-scattering error under 1 %, 99th percentile under 5 %, transmittance within
// 0.02 absolute everywhere. The reference itself is converged: doubling its steps moves it
// by well under those (checked below for one case).
TEST(AerialPerspective, FroxelsAgreeWithPerPixelMarchInStrongHaze) {
    const int W = 192, H = 108;
    const double h0 = 200.0;
    for (const char* preset : {"hazy", "polluted"})
        for (const double sun_azimuth : {10.0, 180.0}) {
            Camera cam = camera_along_x(h0, 2.0 * kDegree);
            SceneDescription s = scene_for(preset, cam, W, H, 6.0, sun_azimuth);
            const std::vector<float> depth = terrain_depth(s, W, H, h0);
            s.aerial.method = AerialOptions::Method::Froxel;
            const AerialPasses f = aerial_perspective(s.aerial_view(), depth, W, H);
            s.aerial.method = AerialOptions::Method::Raymarch;
            const AerialPasses r = aerial_perspective(s.aerial_view(), depth, W, H);
            const Comparison e = compare(f, r, depth);
            EXPECT_LT(e.median_rel_L, 0.01) << preset << " sun azimuth " << sun_azimuth;
            EXPECT_LT(e.p99_rel_L, 0.05) << preset << " sun azimuth " << sun_azimuth;
            EXPECT_LT(e.max_abs_T, 0.02) << preset << " sun azimuth " << sun_azimuth;
            std::printf("%s sun azimuth %.0f: L median %.3f %%, p99 %.3f %%, T max abs %.4f\n", preset,
                        sun_azimuth, 100 * e.median_rel_L, 100 * e.p99_rel_L, e.max_abs_T);
            if (std::string(preset) == "polluted" && sun_azimuth == 10.0) {
                s.aerial.raymarch_steps *= 2;
                const Comparison conv = compare(aerial_perspective(s.aerial_view(), depth, W, H), r, depth);
                EXPECT_LT(conv.p99_rel_L, 0.005);
                EXPECT_LT(conv.max_abs_T, 0.002);
            }
        }
}

// A surface far beyond the atmosphere (the Moon, 3.8e5 km, a few pixels above the ridge)
// must not stretch the volume's depth range: the other pixels keep the tolerances above,
// and the far pixels, marched one by one, get exactly the per-pixel march's values.
TEST(AerialPerspective, FarSurfacesDoNotStretchTheVolume) {
    const int W = 192, H = 108;
    const double h0 = 200.0;
    SceneDescription s = scene_for("hazy", camera_along_x(h0, 2.0 * kDegree), W, H, 6.0, 10.0);
    std::vector<float> depth = terrain_depth(s, W, H, h0);
    std::vector<std::size_t> moon;
    for (int y = 10; y < 13; ++y)
        for (int x = 100; x < 104; ++x) moon.push_back(std::size_t(y) * W + x);  // 12 pixels
    for (std::size_t p : moon) {
        ASSERT_FALSE(std::isfinite(depth[p]));  // sky there
        depth[p] = 3.8e8f;
    }
    s.aerial.method = AerialOptions::Method::Froxel;
    const AerialPasses f = aerial_perspective(s.aerial_view(), depth, W, H);
    s.aerial.method = AerialOptions::Method::Raymarch;
    const AerialPasses r = aerial_perspective(s.aerial_view(), depth, W, H);
    const Comparison e = compare(f, r, depth);
    EXPECT_LT(e.median_rel_L, 0.01);
    EXPECT_LT(e.p99_rel_L, 0.05);
    EXPECT_LT(e.max_abs_T, 0.02);
    for (std::size_t p : moon)
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(f.transmittance[p * 3 + c], r.transmittance[p * 3 + c]);
            EXPECT_EQ(f.inscatter[p * 3 + c], r.inscatter[p * 3 + c]);
            EXPECT_LT(f.transmittance[p * 3 + c], 1.0f);
            EXPECT_GT(f.inscatter[p * 3 + c], 0.0f);
        }
}

// Orthographic and equirectangular cameras through the froxel volume, against the per-pixel
// march, over a ground plane seen from 200 m (out to 60 km), with the tolerances of the
// perspective test. A full panorama spreads the columns over the whole sphere (32 columns
// are 11 degrees apart, and the error reaches 15 % at the horizon, measured): panoramas
// need more columns, 256 x 128 here (measured: median 0.36 %, worst 1.3 %).
TEST(AerialPerspective, OrthographicAndPanoramicCamerasAgreeWithTheMarch) {
    const double h0 = 200.0;
    for (const CameraType type : {CameraType::Orthographic, CameraType::Panoramic}) {
        Camera cam = camera_along_x(h0, 2.0 * kDegree);
        cam.type = type;
        cam.ortho_scale = 500.0;
        const int W = type == CameraType::Panoramic ? 384 : 160, H = type == CameraType::Panoramic ? 192 : 90;
        SceneDescription s = scene_for("hazy", cam, W, H, 10.0, 30.0);
        if (type == CameraType::Panoramic) {
            s.aerial.froxel_width = 256;
            s.aerial.froxel_height = 128;
        }
        const CameraRays rays(cam, W, H);
        std::vector<float> depth(std::size_t(W) * H, std::numeric_limits<float>::infinity());
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const CameraRays::Ray r = rays.at_pixel(x, y);
                if (r.direction.z < 0.0)
                    depth[std::size_t(y) * W + x] =
                        float(std::min(r.origin.z / -r.direction.z, 60e3) / r.distance_per_depth);
            }
        s.aerial.method = AerialOptions::Method::Froxel;
        const AerialPasses f = aerial_perspective(s.aerial_view(), depth, W, H);
        s.aerial.method = AerialOptions::Method::Raymarch;
        const AerialPasses r = aerial_perspective(s.aerial_view(), depth, W, H);
        const Comparison e = compare(f, r, depth);
        std::printf("%s: L median %.3f %%, p99 %.3f %%, T max abs %.4f\n", camera_type_name(type),
                    100 * e.median_rel_L, 100 * e.p99_rel_L, e.max_abs_T);
        EXPECT_LT(e.median_rel_L, 0.01) << camera_type_name(type);
        EXPECT_LT(e.p99_rel_L, 0.05) << camera_type_name(type);
        EXPECT_LT(e.max_abs_T, 0.02) << camera_type_name(type);
    }
}
