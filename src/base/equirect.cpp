// SPDX-License-Identifier: Apache-2.0
// Blender's equirectangular mapping; see equirect.hpp.
//
// Cycles (intern/cycles/kernel/camera/projection.h) writes it as
//     direction_to_equirectangular(dir)
//         = direction_to_equirectangular_range(dir, range = (-2 pi, pi, -pi, pi)),
//     u = (atan2(dir.y, dir.x) - range.y) / range.x,
//     v = (acos(dir.z / |dir|) - range.w) / range.z,
// that is u = 1/2 - atan2(y, x) / (2 pi) and v = 1 - acos(z) / pi = 1/2 + elevation / pi,
// with elevation = atan2(z, hypot(x, y)) (the form used here: it keeps full precision
// near the poles, where acos loses digits). The inverse (equirectangular_to_direction) is
// phi = -2 pi u + pi, theta = pi - pi v, direction = (sin theta cos phi, sin theta sin phi,
// cos theta). +X is the centre of the image (u = 1/2), +Y a quarter from the left
// (u = 1/4), -X both edges.
#include "welkin/base/equirect.hpp"

#include <cmath>

#include "welkin/base/math.hpp"

namespace welkin {

glm::dvec2 direction_to_equirect(const glm::dvec3& d) {
    double u = 0.5 - std::atan2(d.y, d.x) / kTwoPi;
    // atan2 returns values in [-pi, pi]: u in [0, 1]; fold u = 1 (-X seen from below the
    // branch cut) onto u = 0 so that u stays in [0, 1).
    if (u >= 1.0) u -= 1.0;
    if (u < 0.0) u = 0.0;
    const double v = 0.5 + std::atan2(d.z, std::hypot(d.x, d.y)) / kPi;
    return {u, v};
}

glm::dvec3 equirect_to_direction(const glm::dvec2& uv) {
    const double phi = kPi - kTwoPi * uv.x;
    const double elevation = kPi * (uv.y - 0.5);
    const double c = std::cos(elevation);
    return {c * std::cos(phi), c * std::sin(phi), std::sin(elevation)};
}

glm::dvec3 equirect_pixel_direction(int i, int j, int width, int height) {
    // Pixel (i, j) covers u in [i, i + 1] / width and, counted from the top row,
    // v in [1 - (j + 1) / height, 1 - j / height]; its centre is half a pixel in.
    const double u = (double(i) + 0.5) / double(width);
    const double v = 1.0 - (double(j) + 0.5) / double(height);
    return equirect_to_direction({u, v});
}

double equirect_pixel_solid_angle(int j, int width, int height) {
    // Row j spans elevations [pi/2 - pi (j + 1) / height, pi/2 - pi j / height]; a band of
    // elevations [e0, e1] over the full circle has solid angle 2 pi (sin e1 - sin e0).
    // sin(pi/2 - t) = cos(t); cos a - cos b = 2 sin((a + b)/2) sin((b - a)/2) keeps the
    // polar rows (a difference of two numbers near 1) accurate.
    const double t0 = kPi * double(j) / double(height);
    const double t1 = kPi * double(j + 1) / double(height);
    const double band = 2.0 * std::sin(0.5 * (t0 + t1)) * std::sin(0.5 * (t1 - t0));
    return kTwoPi / double(width) * band;
}

}  // namespace welkin
