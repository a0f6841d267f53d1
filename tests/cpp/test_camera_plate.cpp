// SPDX-License-Identifier: Apache-2.0
// The camera plate (camera_plate.hpp) with and without clouds: Combined is the sky plus
// the air's in-scattering, and with clouds exactly the cloud passes' composite over it;
// the ground hides the clouds below the horizon; the sun's disc is dimmed by the cloud's
// transmittance; a bad cloud volume is refused naming clouds.volumes[0].file.
#include <algorithm>
#include <cmath>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/render/camera_plate.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;

namespace {

// A camera `z` m above the origin looking along `forward` (world), +Z up.
Camera camera_looking(const glm::dvec3& forward, double z, double fov_deg) {
    const glm::dvec3 f = glm::normalize(forward);
    const glm::dvec3 right = glm::normalize(glm::cross(f, glm::dvec3(0, 0, 1)));
    const glm::dvec3 up = glm::cross(right, f);
    Camera c;
    c.matrix_world = glm::dmat4(1.0);
    c.matrix_world[0] = glm::dvec4(right, 0.0);
    c.matrix_world[1] = glm::dvec4(up, 0.0);
    c.matrix_world[2] = glm::dvec4(-f, 0.0);
    c.matrix_world[3] = glm::dvec4(0.0, 0.0, z, 1.0);
    c.fov_rad = fov_deg * kDegree;
    return c;
}

SceneDescription plate_scene(int w, int h) {
    SceneDescription s;
    s.method = "lut";
    s.sun_direction = sun_direction_from_angles_deg(8.0, 0.0);
    s.camera = camera_looking({1.0, 0.0, 0.0}, 100.0, 60.0);
    s.resolution = {w, h, 100};
    s.ground = false;  // the passes' algebra over a black ground; the lit ground below
    return s;
}

}  // namespace

TEST(CameraPlate, WithoutCloudsCombinedIsSkyPlusInscatter) {
    const CameraPlate p = render_camera_plate(plate_scene(32, 16));
    const std::size_t n = 32 * 16;
    ASSERT_EQ(p.clouds.size(), n * 4);
    ASSERT_EQ(p.cloud_depth.size(), n);
    int sky = 0, ground = 0;
    for (std::size_t q = 0; q < n; ++q) {
        EXPECT_EQ(p.clouds[q * 4 + 3], 0.0f);
        EXPECT_EQ(p.cloud_depth[q], kNoCloudDepth);
        (std::isinf(p.depth[q]) ? sky : ground)++;
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(p.combined[q * 3 + k], p.sky[q * 3 + k] + p.inscatter[q * 3 + k]);
    }
    EXPECT_GT(sky, 0);
    EXPECT_GT(ground, 0);
}

// A box of cloud 2 km ahead straddling the horizon, and one far below it (under the
// ground as seen from the camera: hidden by it), in front of the sun.
TEST(CameraPlate, CloudsCompositeOverTheSkyAndTheHazedGround) {
    const int W = 48, H = 24;
    SceneDescription s = plate_scene(W, H);
    s.clouds = SceneClouds{};
    s.clouds->lighting.max_steps = 32;
    s.clouds->lighting.min_transmittance = 0.0;
    const test::HomogeneousBox box({2000.0, -300.0, 20.0}, {2600.0, 300.0, 400.0}, 0.004);
    // The clear plate's ground depth is the scene depth the cloud passes end at.
    const CameraPlate clear = render_camera_plate(s);
    const CloudPasses passes = render_cloud_passes(s, box, clear.depth);
    int hidden = 0, seen = 0;
    const CameraRays rays(*s.camera, W, H);
    for (int q = 0; q < W * H; ++q) {
        const CameraRays::Ray r = rays.at_pixel(q % W, q / W);
        // The ray reaches the box's front face (x = 2000) before the ground?
        const double t_box = 2000.0 / r.direction.x;
        const glm::dvec3 at = r.origin + t_box * r.direction;
        const bool in_face = std::abs(at.y) < 300.0 && at.z > 20.0 && at.z < 400.0;
        const bool ground_first =
            std::isfinite(clear.depth[q]) && clear.depth[q] * r.distance_per_depth < t_box;
        if (in_face && !ground_first) {
            ++seen;
            EXPECT_GT(passes.clouds[q * 4 + 3], 0.5f) << q;
        }
        if (ground_first) {
            ++hidden;
            EXPECT_EQ(passes.clouds[q * 4 + 3], 0.0f) << q;
        }
    }
    EXPECT_GT(seen, 4);
    EXPECT_GT(hidden, 4);
}

// The plate with a scene cloud layer: its Welkin.Clouds / CloudDepth are the cloud passes
// of the scene on the plate's ground depth, and Combined their composite over the clear
// plate, pixel by pixel; the sun's disc (in Welkin.Sky) is dimmed by 1 - alpha.
TEST(CameraPlate, PlateCloudPassesAreTheSceneCloudPasses) {
    const int W = 40, H = 20;
    SceneDescription s = plate_scene(W, H);
    // Looking 2.3 degrees up towards the sun (8 degrees up): the disc and the horizon in view.
    s.camera = camera_looking(s.sun_direction - glm::dvec3(0.0, 0.0, 0.1), 100.0, 30.0);
    s.clouds = SceneClouds{};
    CloudLayerParams layer;
    layer.bottom_altitude_m = 600.0;
    layer.top_altitude_m = 1400.0;
    layer.coverage = 0.9;
    layer.density_per_m = 0.05;
    s.clouds->layers.push_back(layer);
    s.clouds->lighting.max_steps = 32;
    SceneDescription clear_scene = s;
    clear_scene.clouds.reset();
    const CameraPlate clear = render_camera_plate(clear_scene);
    const CameraPlate cloudy = render_camera_plate(s);
    const CloudPasses passes = render_cloud_passes(s, clear.depth);
    ASSERT_EQ(cloudy.clouds, passes.clouds);
    ASSERT_EQ(cloudy.cloud_depth, passes.depth);
    EXPECT_EQ(cloudy.sky, clear.sky);
    int cloudy_px = 0;
    for (int q = 0; q < W * H; ++q) {
        const float a = passes.clouds[q * 4 + 3];
        cloudy_px += a > 0.01f;
        for (int k = 0; k < 3; ++k) {
            const float expected =
                passes.clouds[q * 4 + k] + (1.0f - a) * (clear.sky[q * 3 + k] + clear.inscatter[q * 3 + k]);
            EXPECT_FLOAT_EQ(cloudy.combined[q * 3 + k], expected) << q;
        }
    }
    EXPECT_GT(cloudy_px, W * H / 10);
    // The disc's pixel (the brightest of the clear sky) keeps only 1 - alpha of the disc.
    int disc = 0;
    for (int q = 1; q < W * H; ++q)
        if (clear.sky[q * 3 + 1] > clear.sky[disc * 3 + 1]) disc = q;
    std::vector<float> green;
    for (int q = 0; q < W * H; ++q) green.push_back(clear.sky[q * 3 + 1]);
    std::nth_element(green.begin(), green.begin() + W * H / 2, green.end());
    ASSERT_GT(clear.sky[disc * 3 + 1], 100.0f * green[W * H / 2]);  // the disc is in view
    const float a = passes.clouds[disc * 4 + 3];
    EXPECT_GT(a, 0.0f);
    EXPECT_NEAR(cloudy.combined[disc * 3 + 1] - passes.clouds[disc * 4 + 1],
                (1.0f - a) * clear.combined[disc * 3 + 1], 1e-5f * clear.combined[disc * 3 + 1]);
}

TEST(CameraPlate, BadCloudVolumeIsRefusedNamingTheFile) {
    SceneDescription s = plate_scene(8, 4);
    s.clouds = SceneClouds{};
    SceneCloudVolume v;
    v.name = "Cloud";
    v.file = "/nonexistent/cloud.0001.vdb";
    s.clouds->volumes.push_back(v);
    try {
        render_camera_plate(s);
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "clouds.volumes[0].file");
        EXPECT_NE(std::string(e.what()).find("/nonexistent/cloud.0001.vdb"), std::string::npos) << e.what();
    }
}

// The render engine's tiles: a band of a cloudy plate equals the whole plate in its rows.
TEST(CameraPlate, CloudyBandsHaveTheWholePlatesValues) {
    SceneDescription s = plate_scene(24, 12);
    s.clouds = SceneClouds{};
    CloudLayerParams layer;
    layer.bottom_altitude_m = 600.0;
    layer.top_altitude_m = 1400.0;
    layer.coverage = 0.9;
    s.clouds->layers.push_back(layer);
    s.clouds->lighting.max_steps = 16;
    const CameraPlate whole = render_camera_plate(s);
    const CameraPlate band = render_camera_plate(s, nullptr, RowRange{4, 9});
    ASSERT_EQ(band.height, 5);
    const std::size_t q0 = 4 * 24;
    for (std::size_t q = 0; q < band.cloud_depth.size(); ++q) {
        EXPECT_EQ(band.cloud_depth[q], whole.cloud_depth[q0 + q]);
        for (int k = 0; k < 4; ++k) EXPECT_EQ(band.clouds[q * 4 + k], whole.clouds[(q0 + q) * 4 + k]);
        for (int k = 0; k < 3; ++k) EXPECT_EQ(band.combined[q * 3 + k], whole.combined[(q0 + q) * 3 + k]);
    }
}

// The lit ground (camera_plate.hpp): combined = sky + inscatter + T x L_ground, with
// L_ground > 0 on every ground pixel and the sky pixels unchanged; off, the black ground.
TEST(CameraPlate, LitGroundIsAddedThroughTheAir) {
    SceneDescription s = plate_scene(32, 16);
    const CameraPlate off = render_camera_plate(s);
    s.ground = true;
    s.ground_albedo = 0.3;
    const CameraPlate on = render_camera_plate(s);
    int ground = 0;
    for (std::size_t q = 0; q < on.depth.size(); ++q) {
        const bool sky = std::isinf(on.depth[q]);
        ground += sky ? 0 : 1;
        for (int c = 0; c < 3; ++c) {
            const std::size_t k = q * 3 + c;
            EXPECT_EQ(off.combined[k], off.sky[k] + off.inscatter[k]);
            if (sky) {
                EXPECT_EQ(on.combined[k], off.combined[k]);
            } else {
                EXPECT_GT(on.combined[k], off.combined[k]);
                EXPECT_GT(on.transmittance[k], 0.0f);
            }
        }
    }
    EXPECT_GT(ground, 0);
}
