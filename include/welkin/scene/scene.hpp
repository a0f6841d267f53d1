// SPDX-License-Identifier: Apache-2.0
// The scene description (docs/design.md, data flow): everything one frame's sky and
// camera passes depend on, as plain data, in and out of JSON.
//
// One description drives both Blender and the CLI: the add-on writes it from bpy data
// (a few lines: the camera's matrix_world and its Camera data, the sun lamp's direction,
// the render resolution) beside each frame's passes, and `welkin aerial --scene` or
// `welkin sky --scene` reproduces the frame from the JSON alone. The schema is documented
// in docs/pipelines.md ("Scene JSON"); src/scene/json.cpp reads and writes it. to_json writes the
// atmosphere in full (not by preset name), so a file stays valid when a preset changes.
//
// Frame: Blender's world frame, Z up, metres. The scene origin (0, 0, 0) sits
// origin_altitude_m above the ground; the planet centre is straight below it, at
// (0, 0, -(bottom_radius + origin_altitude_m)). A point's altitude is its distance from
// the centre minus bottom_radius, so a camera 10 km away along X at z = 0 stands about
// 8 m higher than the origin (the ground curves away).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <glm/vec3.hpp>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/camera.hpp"
#include "welkin/scene/clouds.hpp"
#include "welkin/sky/method.hpp"

namespace welkin {

// How the aerial-perspective passes are computed (aerial_perspective.hpp).
struct SceneDescription {
    static constexpr int kVersion = 1;
    int version = kVersion;

    Atmosphere atmosphere = Atmosphere::preset(kDefaultPreset);
    double origin_altitude_m = 0.0;                          // the scene origin above the ground, >= 0
    glm::dvec3 sun_direction{0.0, 0.5, 0.8660254037844386};  // towards the sun; normalised
    double exposure = 1.0;                                   // multiplies radiance once, at the output
    ColorSpace color_space = ColorSpace::Rec709;             // of every RGB output (color/color_space.hpp)
    std::string method = "auto";                             // sky method (sky/method.hpp); auto by default
    // The lit ground below the horizon (ground.hpp) in the sky image and the camera plate;
    // its albedo in [0, 1] (unset: the atmosphere's ground_albedo).
    bool ground = true;
    std::optional<double> ground_albedo;
    std::optional<Camera> camera;  // absent: no camera passes can be made
    RenderResolution resolution;
    AerialOptions aerial;
    SkyOptions sky_options;             // LUT sizes and method options
    std::optional<SceneClouds> clouds;  // absent: a clear sky (scene/clouds.hpp)

    // Throws InvalidArgument naming the field (as in the JSON: "camera.lens_mm"). Does not
    // require a camera; camera passes call require_camera().
    void validate() const;
    const Camera& require_camera() const;

    // The observer at the scene origin (for the sky and the sun).
    Observer origin_observer() const { return Observer{origin_altitude_m, sun_direction}.validated(); }
    // The planet centre in the world frame.
    glm::dvec3 planet_centre() const { return {0.0, 0.0, -(atmosphere.bottom_radius_m + origin_altitude_m)}; }
    // What aerial perspective needs of this scene (its camera at its render resolution);
    // throws InvalidArgument naming "camera" when there is none.
    AerialView aerial_view() const;

    // True when the scene has at least one cloud layer or volume.
    bool has_clouds() const { return clouds && !clouds->empty(); }
    // The union of the scene's layers and volumes (opens the VDB files); nullptr without clouds.
    std::shared_ptr<const CloudDensity> cloud_density() const;
    // A fingerprint of what the clouds' view samples (clouds/lighting.hpp, CloudViewCache)
    // depend on: the scene but its sun (its JSON with the sun left out), and each VDB file's
    // size and modification time (a file written again under the same name is another
    // cloud). Two scenes with the same key march the same samples along the same rays.
    std::string cloud_view_key() const;

    // Relative paths in the JSON (clouds.volumes[i].file) are resolved against
    // `base_directory` (from_json_file: the file's folder; empty: the working directory).
    static SceneDescription from_json_string(const std::string& text, const std::string& base_directory = "");
    static SceneDescription from_json_file(const std::string& path);
    std::string to_json_string() const;
    // Refuses to replace an existing file unless `overwrite`; atomic.
    void to_json_file(const std::string& path, bool overwrite = false) const;
};

// Elevation above the XY plane and azimuth counter-clockwise from +X (degrees, as at
// every user edge) to the unit vector towards the sun, and back.
glm::dvec3 sun_direction_from_angles_deg(double elevation_deg, double azimuth_deg);

}  // namespace welkin
