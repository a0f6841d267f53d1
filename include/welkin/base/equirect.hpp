// SPDX-License-Identifier: Apache-2.0
// Blender's equirectangular (Environment Texture) mapping, exactly.
//
// Blender (intern/cycles/kernel/geom/..., direction_to_equirectangular): for a direction
// (x, y, z), Z up,
//     u = -atan2(y, x) / (2 pi) + 1/2,     v = atan2(z, hypot(x, y)) / pi + 1/2,
// u in [0, 1) left to right, v in [0, 1] bottom to top. Files on disk store the top row
// (v = 1, the zenith) first; Blender images store the bottom row first: the flip happens
// once, in the EXR writer's caller, never here.
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace welkin {

glm::dvec2 direction_to_equirect(const glm::dvec3& direction);
glm::dvec3 equirect_to_direction(const glm::dvec2& uv);

// Direction through the centre of pixel (i, j) of a width x height image stored top row
// first (j = 0 is the top row).
glm::dvec3 equirect_pixel_direction(int i, int j, int width, int height);

// Exact solid angle (sr) of a pixel in row j (0 = top): (2 pi / width) times the
// difference of the sines of its bottom and top elevations. The rows sum to 4 pi.
double equirect_pixel_solid_angle(int j, int width, int height);

}  // namespace welkin
