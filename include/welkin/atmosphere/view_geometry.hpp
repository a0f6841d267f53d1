// SPDX-License-Identifier: Apache-2.0
// The angles every method needs for one view direction (Bruneton 2017's r, mu, mu_s, nu).
#pragma once

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "welkin/base/math.hpp"

namespace welkin {

struct ViewGeometry {
    double mu;       // cosine of the view zenith angle
    double mu_s;     // cosine of the sun zenith angle
    double nu;       // cosine of the angle between view and sun
    double cos_phi;  // cosine of the view azimuth relative to the sun's
};

// view: any finite non-zero vector (normalised here); sun: a unit vector; Z up.
inline ViewGeometry view_geometry(const glm::dvec3& view_in, const glm::dvec3& sun) {
    const glm::dvec3 view = view_in / std::sqrt(glm::dot(view_in, view_in));
    ViewGeometry g;
    g.mu = clamp_cosine(view.z);
    g.mu_s = clamp_cosine(sun.z);
    g.nu = clamp_cosine(glm::dot(view, sun));
    const double hv2 = view.x * view.x + view.y * view.y, hs2 = sun.x * sun.x + sun.y * sun.y;
    g.cos_phi = (hv2 > 1e-24 && hs2 > 1e-24)
                    ? clamp_cosine((view.x * sun.x + view.y * sun.y) / std::sqrt(hv2 * hs2))
                    : 1.0;
    return g;
}

}  // namespace welkin
