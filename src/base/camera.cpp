// SPDX-License-Identifier: Apache-2.0
// Camera rays from Blender's camera description; see camera.hpp.
//
// The view plane is Blender's (BKE_camera_params_compute_viewplane): with the fitted
// axis' size `size` (sensor / lens at unit distance for a perspective camera, which is
// 2 tan(fov / 2), or ortho_scale), and viewfac the pixel count along the fitted axis,
// one pixel is size / viewfac across, the plane spans -width/2 .. width/2 pixels
// horizontally and -height/2 .. height/2 vertically, shifted by shift x viewfac pixels.
#include "welkin/base/camera.hpp"

#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {

const char* camera_type_name(CameraType type) {
    switch (type) {
        case CameraType::Perspective:
            return "PERSP";
        case CameraType::Orthographic:
            return "ORTHO";
        case CameraType::Panoramic:
            return "PANO";
    }
    return "PERSP";
}

CameraType camera_type_from_name(const std::string& name, const std::string& parameter) {
    if (name == "PERSP") return CameraType::Perspective;
    if (name == "ORTHO") return CameraType::Orthographic;
    if (name == "PANO") return CameraType::Panoramic;
    throw InvalidArgument(parameter, fmt::format("must be \"PERSP\", \"ORTHO\" or \"PANO\" "
                                                 "(Blender's Camera.type), got \"{}\"",
                                                 name));
}

const char* sensor_fit_name(SensorFit fit) {
    switch (fit) {
        case SensorFit::Auto:
            return "AUTO";
        case SensorFit::Horizontal:
            return "HORIZONTAL";
        case SensorFit::Vertical:
            return "VERTICAL";
    }
    return "AUTO";
}

SensorFit sensor_fit_from_name(const std::string& name, const std::string& parameter) {
    if (name == "AUTO") return SensorFit::Auto;
    if (name == "HORIZONTAL") return SensorFit::Horizontal;
    if (name == "VERTICAL") return SensorFit::Vertical;
    throw InvalidArgument(parameter, fmt::format("must be \"AUTO\", \"HORIZONTAL\" or "
                                                 "\"VERTICAL\" (Blender's Camera.sensor_fit), "
                                                 "got \"{}\"",
                                                 name));
}

void Camera::validate(const std::string& p) const {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            require_finite(fmt::format("{}.matrix_world[{}][{}]", p, r, c), matrix_world[c][r]);
    if (matrix_world[0][3] != 0.0 || matrix_world[1][3] != 0.0 || matrix_world[2][3] != 0.0 ||
        matrix_world[3][3] != 1.0)
        throw InvalidArgument(p + ".matrix_world", "the last row must be [0, 0, 0, 1] (an affine transform)");
    for (int c = 0; c < 3; ++c)
        if (glm::length(glm::dvec3(matrix_world[c])) < 1e-12)
            throw InvalidArgument(p + ".matrix_world",
                                  fmt::format("column {} of the rotation is zero (a camera "
                                              "scaled to nothing)",
                                              c));
    const glm::dvec3 x = glm::normalize(glm::dvec3(matrix_world[0]));
    const glm::dvec3 y = glm::normalize(glm::dvec3(matrix_world[1]));
    const glm::dvec3 z = glm::normalize(glm::dvec3(matrix_world[2]));
    if (std::abs(glm::dot(glm::cross(x, y), z)) < 1e-6)
        throw InvalidArgument(p + ".matrix_world", "the rotation's columns are (nearly) parallel");
    switch (type) {
        case CameraType::Perspective:
            if (fov_rad != 0.0)
                require_in_range(p + ".fov_deg", fov_rad / kDegree, 1e-3, 179.9, "degrees");
            else
                require_in_range(p + ".lens_mm", lens_mm, 1e-3, 1e6, "mm");
            require_in_range(p + ".sensor_width_mm", sensor_width_mm, 1e-3, 1e4, "mm");
            require_in_range(p + ".sensor_height_mm", sensor_height_mm, 1e-3, 1e4, "mm");
            break;
        case CameraType::Orthographic:
            require_in_range(p + ".ortho_scale", ortho_scale, 1e-9, 1e9, "m");
            break;
        case CameraType::Panoramic:
            require_in_range(p + ".latitude_min_deg", latitude_min_rad / kDegree, -90.0, 90.0, "degrees");
            require_in_range(p + ".latitude_max_deg", latitude_max_rad / kDegree, -90.0, 90.0, "degrees");
            require_in_range(p + ".longitude_min_deg", longitude_min_rad / kDegree, -180.0, 180.0, "degrees");
            require_in_range(p + ".longitude_max_deg", longitude_max_rad / kDegree, -180.0, 180.0, "degrees");
            if (!(latitude_min_rad < latitude_max_rad))
                throw InvalidArgument(p + ".latitude_min_deg", "must be below latitude_max_deg");
            if (!(longitude_min_rad < longitude_max_rad))
                throw InvalidArgument(p + ".longitude_min_deg", "must be below longitude_max_deg");
            break;
    }
    require_in_range(p + ".shift_x", shift_x, -100.0, 100.0);
    require_in_range(p + ".shift_y", shift_y, -100.0, 100.0);
    require_in_range(p + ".clip_start_m", clip_start_m, 1e-6, 1e12, "m");
    require_in_range(p + ".clip_end_m", clip_end_m, 1e-6, 1e12, "m");
    if (!(clip_start_m < clip_end_m))
        throw InvalidArgument(p + ".clip_start_m", fmt::format("must be below clip_end_m ({} m), got {} m",
                                                               clip_end_m, clip_start_m));
}

void RenderResolution::validate(const std::string& p) const {
    require_in_range(p + ".x", x, 1, 65536, "pixels");
    require_in_range(p + ".y", y, 1, 65536, "pixels");
    require_in_range(p + ".percentage", percentage, 1, 32767, "%");
    if (width() < 1 || height() < 1)
        throw InvalidArgument(p + ".percentage",
                              fmt::format("{} x {} at {} % is less than one pixel", x, y, percentage));
}

CameraRays::CameraRays(const Camera& camera, int width, int height)
    : type_(camera.type), width_(width), height_(height) {
    camera.validate();
    if (width < 1 || height < 1)
        throw InvalidArgument("resolution",
                              fmt::format("must be at least 1 x 1, got {} x {}", width, height));
    const glm::dmat4& m = camera.matrix_world;
    position_ = glm::dvec3(m[3]);
    right_ = glm::normalize(glm::dvec3(m[0]));
    // Orthonormalise (Gram-Schmidt), keeping the view axis exact.
    back_ = glm::normalize(glm::dvec3(m[2]));
    right_ = glm::normalize(right_ - glm::dot(right_, back_) * back_);
    up_ = glm::cross(back_, right_);
    if (glm::dot(up_, glm::dvec3(m[1])) < 0.0)  // a mirrored camera: keep Blender's +Y up
        up_ = -up_;

    if (type_ == CameraType::Panoramic) {
        lat_min_ = camera.latitude_min_rad;
        lat_max_ = camera.latitude_max_rad;
        lon_min_ = camera.longitude_min_rad;
        lon_max_ = camera.longitude_max_rad;
        return;
    }
    // Blender's BKE_camera_sensor_fit and BKE_camera_sensor_size.
    const bool horizontal = camera.sensor_fit == SensorFit::Horizontal ||
                            (camera.sensor_fit == SensorFit::Auto && width >= height);
    double size;
    if (type_ == CameraType::Orthographic)
        size = camera.ortho_scale;
    else if (camera.fov_rad > 0.0)
        size = 2.0 * std::tan(0.5 * camera.fov_rad);
    else
        size = (camera.sensor_fit == SensorFit::Vertical ? camera.sensor_height_mm : camera.sensor_width_mm) /
               camera.lens_mm;
    const double viewfac = horizontal ? double(width) : double(height);
    const double pixel = size / viewfac;
    w_ = pixel * double(width);
    h_ = pixel * double(height);
    x0_ = -0.5 * w_ + camera.shift_x * size;
    y0_ = -0.5 * h_ + camera.shift_y * size;
}

CameraRays::Ray CameraRays::at_screen(double sx, double sy) const {
    Ray ray;
    if (type_ == CameraType::Panoramic) {
        // Cycles (equirectangular_range_to_direction): u = sx, v = 1 - sy (its images are
        // bottom row first), latitude = lat_min + (lat_max - lat_min) v and
        // phi = -(lon_min + (lon_max - lon_min) u), the direction
        // (cos lat cos phi, cos lat sin phi, sin lat) in a frame whose x is forward (local
        // -Z), y is left (local -X) and z is up (local +Y).
        const double lat = lat_min_ + (lat_max_ - lat_min_) * (1.0 - sy);
        const double phi = -(lon_min_ + (lon_max_ - lon_min_) * sx);
        const double c = std::cos(lat);
        const glm::dvec3 local_dir{-c * std::sin(phi), std::sin(lat), -c * std::cos(phi)};
        ray.origin = position_;
        ray.direction = glm::normalize(local_dir.x * right_ + local_dir.y * up_ + local_dir.z * back_);
        ray.distance_per_depth = 1.0;  // the Z pass of a panorama is the distance itself
        return ray;
    }
    const double px = x0_ + w_ * sx;
    const double py = y0_ + h_ * (1.0 - sy);
    if (type_ == CameraType::Orthographic) {
        ray.origin = position_ + px * right_ + py * up_;
        ray.direction = -back_;
        ray.distance_per_depth = 1.0;
        return ray;
    }
    const glm::dvec3 d = px * right_ + py * up_ - back_;
    const double len = glm::length(d);
    ray.origin = position_;
    ray.direction = d / len;
    ray.distance_per_depth = len;  // the point at depth z along the axis is z d
    return ray;
}

glm::dvec3 CameraRays::view_vector(const glm::dvec3& direction) const {
    // Blender hands Cycles the camera's matrix times scale(1, 1, -1): its camera space is the
    // object's local frame with z flipped (forward, where the camera looks).
    return glm::normalize(
        glm::dvec3(glm::dot(direction, right_), glm::dot(direction, up_), -glm::dot(direction, back_)));
}

CameraRays::Ray CameraRays::at_view_vector(double vx, double vy) const {
    if (type_ != CameraType::Perspective)
        throw InvalidArgument("camera.type", "a ray along a view vector needs a perspective camera");
    const double vz2 = 1.0 - vx * vx - vy * vy;
    if (!(vz2 > 0.0))
        throw InvalidArgument("view_vector",
                              fmt::format("({:g}, {:g}) is not the x, y of a unit vector ahead", vx, vy));
    const double vz = std::sqrt(vz2);
    Ray ray;
    ray.origin = position_;
    ray.direction = glm::normalize(vx * right_ + vy * up_ - vz * back_);
    ray.distance_per_depth = 1.0 / vz;
    return ray;
}

}  // namespace welkin
