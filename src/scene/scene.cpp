// SPDX-License-Identifier: Apache-2.0
// The scene description's checks and small conversions; see scene.hpp. The JSON form is
// in src/scene/json.cpp.
#include "welkin/scene/scene.hpp"

#include <cmath>
#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {

void SceneDescription::validate() const {
    if (ground_albedo) require_in_range("ground.albedo", *ground_albedo, 0.0, 1.0);
    if (version < 1 || version > kVersion)
        throw InvalidArgument("version", fmt::format("must be in [1, {}] (this Welkin reads scene "
                                                     "descriptions up to version {}), got {}",
                                                     kVersion, kVersion, version));
    try {
        atmosphere.validate();
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("atmosphere." + e.parameter(), e.what());
    }
    require_in_range("origin_altitude_m", origin_altitude_m, 0.0, 1e9, "m");
    for (int i = 0; i < 3; ++i) require_finite("sun.direction", sun_direction[i]);
    if (glm::length(sun_direction) < 1e-12)
        throw InvalidArgument("sun.direction", "must be a non-zero vector (towards the sun)");
    require_in_range("exposure", exposure, 1e-12, 1e6);
    try {
        sky_options.validate();
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("sky_options." + e.parameter(), e.what());
    }
    make_sky_method(method, sky_options);  // an unknown name throws, naming "method"
    if (camera) camera->validate("camera");
    resolution.validate("resolution");
    aerial.validate("aerial");
    if (clouds) clouds->validate(atmosphere.bottom_radius_m, origin_altitude_m);
}

std::shared_ptr<const CloudDensity> SceneDescription::cloud_density() const {
    if (!has_clouds()) return nullptr;
    return make_scene_cloud_density(*clouds, atmosphere.bottom_radius_m, origin_altitude_m);
}

std::string SceneDescription::cloud_view_key() const {
    SceneDescription unlit = *this;
    unlit.sun_direction = SceneDescription{}.sun_direction;
    std::string key = unlit.to_json_string();
    if (clouds)
        for (const auto& v : clouds->volumes) {
            // A file that cannot be read: no stamp (cloud_density() refuses it).
            std::error_code size_error, time_error;
            const auto size = std::filesystem::file_size(v.file, size_error);
            const auto time = std::filesystem::last_write_time(v.file, time_error);
            key += fmt::format("|{}:{}:{}", v.file, size_error ? 0 : size,
                               time_error ? 0 : time.time_since_epoch().count());
        }
    return key;
}

const Camera& SceneDescription::require_camera() const {
    if (!camera)
        throw InvalidArgument("camera",
                              "the scene has no camera (an object \"camera\" with "
                              "matrix_world and type is needed for camera passes)");
    return *camera;
}

glm::dvec3 sun_direction_from_angles_deg(double elevation_deg, double azimuth_deg) {
    require_in_range("sun.elevation_deg", elevation_deg, -90.0, 90.0, "degrees");
    require_in_range("sun.azimuth_deg", azimuth_deg, -360.0, 360.0, "degrees");
    const double e = elevation_deg * kDegree, a = azimuth_deg * kDegree;
    return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

AerialView SceneDescription::aerial_view() const {
    return AerialView{atmosphere,         sky_options.luts(),  origin_observer(), require_camera(),
                      resolution.width(), resolution.height(), exposure,          aerial,
                      color_space};
}

}  // namespace welkin
