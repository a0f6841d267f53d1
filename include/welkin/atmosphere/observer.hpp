// SPDX-License-Identifier: Apache-2.0
// Where the sky is seen from: the observer's altitude and the direction towards the sun.
//
// Frame: Blender's world frame, Z up. The observer stands on the Z axis at
// bottom_radius + altitude_m from the planet centre, which lies straight below.
#pragma once

#include <span>

#include <glm/vec3.hpp>

namespace welkin {

struct Observer {
    double altitude_m = 0.0;                  // above the ground; may exceed the atmosphere's top
    glm::dvec3 sun_direction{0.0, 0.0, 1.0};  // unit vector towards the sun, Z up

    // Throws InvalidArgument (altitude below 0 or non-finite, sun not a finite non-zero
    // vector). Normalises sun_direction.
    Observer validated() const;
};

// Throws InvalidArgument naming view_directions[i] for the first direction that is not a
// finite non-zero vector. Methods normalise each direction as they use it.
void validate_directions(std::span<const glm::dvec3> directions);

}  // namespace welkin
