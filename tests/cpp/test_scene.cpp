// SPDX-License-Identifier: Apache-2.0
// The scene description (JSON round trip, errors naming the key) and the camera rays
// (Blender's view plane, sensor fit, shift, orthographic and equirectangular cameras).
#include <cmath>
#include <string>
#include <utility>

#include "invalid_argument_testing.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/base/camera.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
using welkin::test::parameter_of;

namespace {

std::string scene_with(const std::string& extra) {
    return R"({"version": 1, "camera": {"matrix_world": [[1,0,0,0],[0,1,0,0],[0,0,1,2],[0,0,0,1]],
               "type": "PERSP"})" +
           extra + "}";
}

glm::dvec3 local(const CameraRays& rays, const Camera& cam, const glm::dvec3& world) {
    (void)rays;
    const glm::dmat3 r(cam.matrix_world);
    return glm::transpose(r) * world;  // rotation only (orthonormal here)
}

}  // namespace

TEST(Scene, JsonRoundTripIsExact) {
    SceneDescription s = SceneDescription::from_json_string(R"({
        "version": 1, "atmosphere": "hazy", "origin_altitude_m": 250,
        "sun": {"elevation_deg": 10, "azimuth_deg": 45}, "exposure": 2, "method": "raymarch",
        "camera": {"matrix_world": [[0,0,1,5],[1,0,0,-3],[0,1,0,40],[0,0,0,1]], "type": "ORTHO",
                   "ortho_scale": 12.5, "shift_x": 0.1, "shift_y": -0.2, "sensor_fit": "VERTICAL",
                   "clip_start_m": 0.5, "clip_end_m": 5e4},
        "resolution": {"x": 640, "y": 480, "percentage": 50},
        "aerial": {"method": "raymarch", "froxels": [16, 24, 40], "raymarch_steps": 99}})");
    EXPECT_EQ(s.atmosphere.name, Atmosphere::preset("hazy").name);
    EXPECT_EQ(s.resolution.width(), 320);
    EXPECT_EQ(s.resolution.height(), 240);
    ASSERT_TRUE(s.camera);
    EXPECT_EQ(s.camera->matrix_world[3][0], 5.0);  // row 0, column 3: translation x
    EXPECT_EQ(s.camera->matrix_world[0][1], 1.0);  // row 1, column 0
    EXPECT_EQ(s.aerial.froxel_slices, 40);
    EXPECT_NEAR(s.sun_direction.z, std::sin(10 * kDegree), 1e-15);
    const std::string text = s.to_json_string();
    const SceneDescription back = SceneDescription::from_json_string(text);
    EXPECT_EQ(back.to_json_string(), text);  // the written form reproduces itself exactly
    EXPECT_EQ(back.atmosphere.mie_extinction, s.atmosphere.mie_extinction);
    EXPECT_EQ(back.camera->matrix_world, s.camera->matrix_world);
    EXPECT_EQ(back.camera->type, CameraType::Orthographic);
    EXPECT_EQ(back.aerial.method, AerialOptions::Method::Raymarch);
    EXPECT_EQ(back.sun_direction, s.sun_direction);
}

TEST(Scene, ErrorsNameTheKey) {
    EXPECT_EQ(parameter_of([] { SceneDescription::from_json_string("{}"); }), "version");
    EXPECT_EQ(parameter_of([] { SceneDescription::from_json_string(R"({"version": 2})"); }), "version");
    EXPECT_EQ(parameter_of([] { SceneDescription::from_json_string("{"); }), "scene JSON");
    EXPECT_EQ(parameter_of([] { SceneDescription::from_json_string(R"({"version":1,"exposre":1})"); }),
              "exposre");
    EXPECT_EQ(
        parameter_of([] { SceneDescription::from_json_string(R"({"version":1,"atmosphere":"nope"})"); }),
        "atmosphere.preset");
    EXPECT_EQ(parameter_of([] {
                  SceneDescription::from_json_string(
                      R"({"version":1,"atmosphere":{"preset":"clear","mie":{"g":3}}})");
              }),
              "atmosphere.mie.g");
    EXPECT_EQ(parameter_of([] {
                  SceneDescription::from_json_string(
                      R"({"version":1,"sun":{"direction":[0,0,1],"elevation_deg":3}})");
              }),
              "sun");
    EXPECT_EQ(parameter_of(
                  [] { SceneDescription::from_json_string(R"({"version":1,"sun":{"direction":[0,0,0]}})"); }),
              "sun.direction");
    EXPECT_EQ(
        parameter_of([] {
            SceneDescription::from_json_string(R"({"version":1,"sun":{"elevation_deg":95,"azimuth_deg":0}})");
        }),
        "sun.elevation_deg");
    EXPECT_EQ(
        parameter_of([] { SceneDescription::from_json_string(R"({"version":1,"origin_altitude_m":-1})"); }),
        "origin_altitude_m");
    EXPECT_EQ(
        parameter_of([] { SceneDescription::from_json_string(scene_with(R"(, "resolution": {"x": 0})")); }),
        "resolution.x");
    EXPECT_EQ(parameter_of(
                  [] { SceneDescription::from_json_string(R"({"version":1,"camera":{"type":"PERSP"}})"); }),
              "camera.matrix_world");
    EXPECT_EQ(parameter_of([] {
                  SceneDescription::from_json_string(
                      R"({"version":1,"camera":{"type":"PERSP","matrix_world":[[1,0,0],[0,1,0],[0,0,1]]}})");
              }),
              "camera.matrix_world");
    EXPECT_EQ(
        parameter_of([] {
            SceneDescription::from_json_string(
                R"({"version":1,"camera":{"type":"PERSP","matrix_world":[[0,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}})");
        }),
        "camera.matrix_world");
    EXPECT_EQ(
        parameter_of([] {
            SceneDescription::from_json_string(
                R"({"version":1,"camera":{"type":"PERSP","matrix_world":[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,2]]}})");
        }),
        "camera.matrix_world");
    EXPECT_EQ(parameter_of([] { SceneDescription::from_json_string(scene_with(R"(, "x": 1)")).camera; }),
              "x");
    // Inside the camera object.
    const auto camera_error = [](const std::string& fields) {
        return parameter_of([&] {
            SceneDescription::from_json_string(
                R"({"version":1,"camera":{"matrix_world":[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],)" +
                fields + "}}");
        });
    };
    EXPECT_EQ(camera_error(R"("type": "FISH")"), "camera.type");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "lens_mm": -5)"), "camera.lens_mm");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "lens_mm": 5, "fov_deg": 30)"), "camera.fov_deg");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "fov_deg": 180)"), "camera.fov_deg");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "sensor_fit": "auto")"), "camera.sensor_fit");
    EXPECT_EQ(camera_error(R"("type": "ORTHO", "ortho_scale": 0)"), "camera.ortho_scale");
    EXPECT_EQ(camera_error(R"("type": "PANO", "panorama_type": "FISHEYE_EQUISOLID")"),
              "camera.panorama_type");
    EXPECT_EQ(camera_error(R"("type": "PANO", "latitude_min_deg": 10, "latitude_max_deg": 5)"),
              "camera.latitude_min_deg");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "clip_start_m": 10, "clip_end_m": 5)"), "camera.clip_start_m");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "focal": 5)"), "camera.focal");
    EXPECT_EQ(camera_error(R"("type": "PERSP", "shift_x": "a")"), "camera.shift_x");
    // Aerial options.
    EXPECT_EQ(parameter_of([] {
                  SceneDescription::from_json_string(R"({"version":1,"aerial":{"froxels":[1,32,32]}})");
              }),
              "aerial.froxels[0]");
    EXPECT_EQ(parameter_of(
                  [] { SceneDescription::from_json_string(R"({"version":1,"aerial":{"method":"fast"}})"); }),
              "aerial.method");
    EXPECT_EQ(parameter_of([] { SceneDescription::from_json_string(R"({"version":1,"method":"magic"})"); }),
              "method");
    // No camera is allowed in the description, refused where one is needed.
    const SceneDescription no_camera = SceneDescription::from_json_string(R"({"version":1})");
    EXPECT_EQ(parameter_of([&] { no_camera.require_camera(); }), "camera");
}

TEST(Scene, SunAnglesFollowTheConvention) {
    // Azimuth counter-clockwise from +X, elevation above the XY plane.
    const glm::dvec3 s = sun_direction_from_angles_deg(30.0, 90.0);
    EXPECT_NEAR(s.x, 0.0, 1e-15);
    EXPECT_NEAR(s.y, std::cos(30 * kDegree), 1e-15);
    EXPECT_NEAR(s.z, 0.5, 1e-15);
    const SceneDescription d = SceneDescription::from_json_string(
        R"({"version":1,"sun":{"direction":[0,0,3]},"origin_altitude_m":100})");
    EXPECT_NEAR(d.origin_observer().sun_direction.z, 1.0, 1e-15);  // normalised
    EXPECT_DOUBLE_EQ(d.planet_centre().z, -(d.atmosphere.bottom_radius_m + 100.0));
}

// Blender's view plane: a 36 mm sensor behind a 50 mm lens spans x in [-0.36, 0.36] at
// unit distance across the width (horizontal fit), the height in proportion.
TEST(CameraRays, PerspectiveViewPlaneIsBlenders) {
    Camera cam;  // identity: looks down world -Z, +Y up
    const CameraRays rays(cam, 1920, 1080);
    const auto dir_at = [&](double sx, double sy) {
        const CameraRays::Ray r = rays.at_screen(sx, sy);
        return r.direction / -r.direction.z;  // point on the plane z = -1
    };
    EXPECT_NEAR(dir_at(0.0, 0.5).x, -0.36, 1e-12);
    EXPECT_NEAR(dir_at(1.0, 0.5).x, 0.36, 1e-12);
    EXPECT_NEAR(dir_at(0.5, 0.0).y, 0.36 * 1080.0 / 1920.0, 1e-12);  // top row is +Y
    EXPECT_NEAR(rays.at_screen(0.5, 0.5).distance_per_depth, 1.0, 1e-15);
    // Depth along the axis z reaches the point z * distance_per_depth along the ray.
    const CameraRays::Ray corner = rays.at_screen(1.0, 0.0);
    EXPECT_NEAR(-(corner.direction * corner.distance_per_depth).z, 1.0, 1e-12);

    // Portrait render, AUTO: the sensor width fits the larger axis, the height.
    const CameraRays portrait(cam, 1080, 1920);
    const CameraRays::Ray top = portrait.at_screen(0.5, 0.0);
    EXPECT_NEAR(top.direction.y / -top.direction.z, 0.36, 1e-12);
    // VERTICAL: sensor_height_mm across the height.
    Camera v = cam;
    v.sensor_fit = SensorFit::Vertical;
    const CameraRays vr(v, 1920, 1080);
    const CameraRays::Ray vt = vr.at_screen(0.5, 0.0);
    EXPECT_NEAR(vt.direction.y / -vt.direction.z, 0.24, 1e-12);
    // Field of view replaces the lens: 90 degrees across the width.
    Camera f = cam;
    f.fov_rad = 90.0 * kDegree;
    const CameraRays::Ray fr = CameraRays(f, 200, 100).at_screen(1.0, 0.5);
    EXPECT_NEAR(fr.direction.x / -fr.direction.z, 1.0, 1e-12);
    // Shift: in units of the fitted axis (the width): 0.5 moves the centre by 0.36.
    Camera s = cam;
    s.shift_x = 0.5;
    s.shift_y = -0.25;
    const CameraRays::Ray sc = CameraRays(s, 1920, 1080).at_screen(0.5, 0.5);
    EXPECT_NEAR(sc.direction.x / -sc.direction.z, 0.36, 1e-12);
    EXPECT_NEAR(sc.direction.y / -sc.direction.z, -0.18, 1e-12);
}

TEST(CameraRays, MatrixWorldPlacesAndTurnsTheCamera) {
    // Blender's usual "look along +X" camera: rotation (90, 0, -90) degrees -> local -Z is
    // world +X, local +Y is world +Z, local +X is world -Y.
    Camera cam;
    cam.matrix_world = glm::dmat4(glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 1, 0), glm::dvec4(-1, 0, 0, 0),
                                  glm::dvec4(10, 20, 30, 1));
    const CameraRays rays(cam, 101, 101);
    const CameraRays::Ray c = rays.at_screen(0.5, 0.5);
    EXPECT_NEAR(glm::distance(c.direction, glm::dvec3(1, 0, 0)), 0.0, 1e-12);
    EXPECT_EQ(c.origin, glm::dvec3(10, 20, 30));
    const CameraRays::Ray right = rays.at_screen(1.0, 0.5);
    EXPECT_LT(right.direction.y, 0.0);  // the right of the image is world -Y
    EXPECT_NEAR(glm::length(local(rays, cam, right.direction)), 1.0, 1e-12);
    // A scaled camera sees the same rays (the scale is ignored, as in Cycles).
    Camera scaled = cam;
    for (int k = 0; k < 3; ++k) scaled.matrix_world[k] *= 3.0;
    const CameraRays::Ray sr = CameraRays(scaled, 101, 101).at_screen(0.2, 0.7);
    EXPECT_NEAR(glm::distance(sr.direction, rays.at_screen(0.2, 0.7).direction), 0.0, 1e-12);
}

// Cycles' View Vector: the camera's local frame with z flipped (x right, y up, z ahead),
// normalised; at_view_vector is its inverse for a perspective camera, shift and turn included.
TEST(CameraRays, ViewVectorIsCyclesCameraSpace) {
    Camera cam;
    cam.matrix_world = glm::dmat4(glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 1, 0), glm::dvec4(-1, 0, 0, 0),
                                  glm::dvec4(10, 20, 30, 1));
    cam.shift_x = 0.2;
    cam.shift_y = -0.1;
    const CameraRays rays(cam, 640, 360);
    EXPECT_NEAR(glm::distance(rays.view_vector(glm::dvec3(1, 0, 0)), glm::dvec3(0, 0, 1)), 0.0, 1e-15);
    EXPECT_NEAR(glm::distance(rays.view_vector(glm::dvec3(0, -1, 0)), glm::dvec3(1, 0, 0)), 0.0, 1e-15);
    EXPECT_NEAR(glm::distance(rays.view_vector(glm::dvec3(0, 0, 1)), glm::dvec3(0, 1, 0)), 0.0, 1e-15);
    for (const auto& [sx, sy] : {std::pair{0.0, 0.0}, {1.0, 0.3}, {0.4, 1.0}, {-0.05, 1.05}}) {
        const CameraRays::Ray r = rays.at_screen(sx, sy);
        const glm::dvec3 v = rays.view_vector(r.direction);
        EXPECT_NEAR(glm::length(v), 1.0, 1e-14);
        const CameraRays::Ray back = rays.at_view_vector(v.x, v.y);
        EXPECT_NEAR(glm::distance(back.direction, r.direction), 0.0, 1e-12);
        EXPECT_EQ(back.origin, r.origin);
        EXPECT_NEAR(back.distance_per_depth, r.distance_per_depth, 1e-12);  // 1 / z: the depth's
    }
    EXPECT_THROW((void)rays.at_view_vector(0.8, 0.7), InvalidArgument);  // not a unit vector ahead
    Camera ortho;
    ortho.type = CameraType::Orthographic;
    EXPECT_THROW((void)CameraRays(ortho, 64, 64).at_view_vector(0.0, 0.0), InvalidArgument);
}

TEST(CameraRays, OrthographicRaysAreParallel) {
    Camera cam;
    cam.type = CameraType::Orthographic;
    cam.ortho_scale = 8.0;
    const CameraRays rays(cam, 400, 200);
    const CameraRays::Ray a = rays.at_screen(0.0, 0.0), b = rays.at_screen(1.0, 1.0);
    EXPECT_EQ(a.direction, glm::dvec3(0, 0, -1));
    EXPECT_EQ(b.direction, glm::dvec3(0, 0, -1));
    EXPECT_NEAR(a.origin.x, -4.0, 1e-12);
    EXPECT_NEAR(a.origin.y, 2.0, 1e-12);
    EXPECT_NEAR(b.origin.x, 4.0, 1e-12);
    EXPECT_EQ(a.distance_per_depth, 1.0);
}

// A full equirectangular panorama pointed along world +X is Blender's Environment
// Texture mapping: the pixel at (u, 1 - v) looks along equirect_to_direction(u, v).
TEST(CameraRays, PanoramaPointedAlongXIsTheEnvironmentMapping) {
    Camera cam;
    cam.type = CameraType::Panoramic;
    cam.matrix_world = glm::dmat4(glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 1, 0), glm::dvec4(-1, 0, 0, 0),
                                  glm::dvec4(0, 0, 0, 1));
    const CameraRays rays(cam, 64, 32);
    for (double u : {0.03, 0.25, 0.5, 0.61, 0.97})
        for (double v : {0.05, 0.3, 0.5, 0.8, 0.99}) {
            const glm::dvec3 expected = equirect_to_direction({u, v});
            const CameraRays::Ray r = rays.at_screen(u, 1.0 - v);
            EXPECT_NEAR(glm::distance(r.direction, expected), 0.0, 1e-12) << u << " " << v;
            EXPECT_EQ(r.distance_per_depth, 1.0);
        }
}
