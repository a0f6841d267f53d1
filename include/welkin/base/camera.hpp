// SPDX-License-Identifier: Apache-2.0
// A render camera as Blender describes it, and the rays its pixels see.
//
// The description is Blender's own (bpy.types.Camera and Object.matrix_world), so that
// the add-on writes it from bpy data in a few lines and a frame can be reproduced from
// its JSON alone (scene.hpp):
//   matrix_world  4 x 4, camera to world, Blender's world frame (Z up, metres). The
//                 camera looks down its local -Z with local +Y up and +X to the right.
//                 Scale is ignored (Cycles clears it too): the rotation part is
//                 orthonormalised column by column.
//   type          Perspective ("PERSP"), Orthographic ("ORTHO") or Panoramic ("PANO",
//                 equirectangular only: Cycles' panorama_type "EQUIRECTANGULAR").
//   perspective   lens_mm with sensor_width_mm / sensor_height_mm and sensor_fit, or the
//                 field of view fov_rad (Blender's Camera.angle: across the fitted axis).
//   orthographic  ortho_scale: the view's size across the fitted axis, metres.
//   shift_x/y     Blender's lens shift, in units of the fitted axis' size (ignored by
//                 panoramic cameras, as in Cycles).
//   clip range    clip_start_m < clip_end_m, as Blender's.
//
// Sensor fit (Blender's BKE_camera_sensor_fit): AUTO fits sensor_width_mm (or the field
// of view, or ortho_scale) to the larger of the render's width and height; HORIZONTAL fits
// sensor_width_mm to the width; VERTICAL fits sensor_height_mm to the height. Pixels are
// square.
//
// Pixels. A render is width x height pixels, row 0 at the top (as in EXR files; Blender's
// own images are bottom row first and are flipped once, at the add-on's edge). Screen
// coordinates (sx, sy) are in [0, 1] x [0, 1], left to right and top to bottom: pixel
// (i, j)'s centre is ((i + 0.5) / width, (j + 0.5) / height).
//
// Depth. Blender's Z pass (Cycles' camera_z_depth) is the distance along the view axis
// (local -Z) for perspective and orthographic cameras, and the distance along the ray for
// panoramic ones. Ray::distance_per_depth converts: distance along the ray = depth x it.
//
// Equirectangular panoramas follow Cycles (equirectangular_range_to_direction): the
// image's centre looks down local -Z, its top towards local +Y, longitude growing to the
// left; with the camera pointed along world +X the image is Blender's Environment Texture
// mapping. Orthographic rays start on the camera's plane (local z = 0), perspective and
// panoramic ones at the camera's position.
#pragma once

#include <string>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace welkin {

enum class CameraType { Perspective, Orthographic, Panoramic };
enum class SensorFit { Auto, Horizontal, Vertical };

// Blender's enum identifiers: "PERSP", "ORTHO", "PANO"; "AUTO", "HORIZONTAL", "VERTICAL".
const char* camera_type_name(CameraType type);
CameraType camera_type_from_name(const std::string& name, const std::string& parameter);
const char* sensor_fit_name(SensorFit fit);
SensorFit sensor_fit_from_name(const std::string& name, const std::string& parameter);

struct Camera {
    glm::dmat4 matrix_world{1.0};  // camera to world (glm: column-major, m[col][row])
    CameraType type = CameraType::Perspective;

    double lens_mm = 50.0;
    double sensor_width_mm = 36.0, sensor_height_mm = 24.0;
    SensorFit sensor_fit = SensorFit::Auto;
    double fov_rad = 0.0;  // > 0: the field of view across the fitted axis, replaces lens_mm

    double ortho_scale = 6.0;  // metres across the fitted axis

    // Equirectangular range (Cycles' latitude_min .. longitude_max), radians.
    double latitude_min_rad = -1.5707963267948966, latitude_max_rad = 1.5707963267948966;
    double longitude_min_rad = -3.141592653589793, longitude_max_rad = 3.141592653589793;

    double shift_x = 0.0, shift_y = 0.0;
    double clip_start_m = 0.1, clip_end_m = 1000.0;

    // Throws InvalidArgument naming `parameter`.<field> and its accepted range.
    void validate(const std::string& parameter = "camera") const;
};

// Blender's render resolution: resolution_x, resolution_y and resolution_percentage; the
// rendered image is floor(x * percentage / 100) by floor(y * percentage / 100) pixels.
struct RenderResolution {
    int x = 1920, y = 1080, percentage = 100;

    int width() const { return int(long(x) * percentage / 100); }
    int height() const { return int(long(y) * percentage / 100); }
    // x, y in [1, 65536], percentage in [1, 32767] (Blender's ranges), the result at
    // least 1 x 1.
    void validate(const std::string& parameter = "resolution") const;
};

// The world-space rays of a camera rendering width x height pixels.
class CameraRays {
public:
    CameraRays(const Camera& camera, int width, int height);

    struct Ray {
        glm::dvec3 origin;          // world, metres
        glm::dvec3 direction;       // world, unit
        double distance_per_depth;  // distance along the ray per unit of Z-pass depth (>= 1)
    };

    // Screen coordinates in [0, 1] (see above); values outside extrapolate the projection.
    Ray at_screen(double sx, double sy) const;
    Ray at_pixel(int i, int j) const {
        return at_screen((double(i) + 0.5) / double(width_), (double(j) + 0.5) / double(height_));
    }

    // Cycles' camera space (Camera Data > View Vector): x right, y up, z forward. The unit
    // camera-space vector of a world direction, and for a perspective camera the ray along
    // the camera-space direction (vx, vy, sqrt(1 - vx^2 - vy^2)) (vx^2 + vy^2 < 1).
    glm::dvec3 view_vector(const glm::dvec3& direction) const;
    Ray at_view_vector(double vx, double vy) const;
    CameraType type() const { return type_; }

    int width() const { return width_; }
    int height() const { return height_; }
    glm::dvec3 position() const { return position_; }

private:
    CameraType type_;
    int width_, height_;
    glm::dvec3 position_, right_, up_, back_;  // world; back = local +Z
    // Perspective and orthographic: the view plane (at unit distance, or the ortho plane)
    // spans [x0, x0 + w] x [y0, y0 + h] in local x, y.
    double x0_ = 0, y0_ = 0, w_ = 0, h_ = 0;
    double lat_min_ = 0, lat_max_ = 0, lon_min_ = 0, lon_max_ = 0;
};

}  // namespace welkin
