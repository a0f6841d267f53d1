// SPDX-License-Identifier: Apache-2.0
// The clouds' transmittance towards a distant light (the sun) from many points: what the
// Blender add-on's cloud shadows need (the sun lamp dimmed by the clouds over the scene, a
// map of the shadow they cast on the ground).
//
// For a point p and a unit direction w towards the light, the direct beam that reaches p
// has crossed the clouds along the ray p + t w, t in [0, max_distance]; by Beer-Lambert
// (the clouds' extinction is grey, density.hpp) its transmittance is
//
//     T(p) = exp(-tau),   tau = integral over t of sigma_t(p + t w) dt,
//
// tau by march_optical_depth (depth_grid.hpp): the midpoint rule over the density's
// majorant segments, `steps` steps spread over them in proportion to their lengths (at
// least one per segment; exact for a homogeneous medium). The air's own
// transmittance is not included (the sun's irradiance at the ground carries it already).
#pragma once

#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/base/progress.hpp"
#include "welkin/clouds/density.hpp"

namespace welkin {

struct CloudShadowOptions {
    int steps = 64;                 // march steps per ray, [1, 65536]
    double max_distance_m = 1.0e6;  // how far along the ray clouds count, > 0
    void validate() const;          // InvalidArgument naming "steps" / "max_distance_m"
};

// T(p) for each point (world frame, metres), towards `direction` (normalised here; a zero
// or non-finite direction is InvalidArgument "direction"). Parallel over the points;
// `progress` may cancel (welkin::Cancelled).
std::vector<float> cloud_transmittance(const CloudDensity& density, std::span<const glm::dvec3> points,
                                       const glm::dvec3& direction, const CloudShadowOptions& options = {},
                                       Progress* progress = nullptr);

}  // namespace welkin
