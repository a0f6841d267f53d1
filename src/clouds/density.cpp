// SPDX-License-Identifier: Apache-2.0
// Cloud density sources: shared geometry; see clouds/density.hpp.
#include "welkin/clouds/density.hpp"

#include <algorithm>
#include <cmath>

namespace welkin {

// Slab method: for each axis the ray is inside the slab lo <= o + t d <= hi for t between
// (lo - o) / d and (hi - o) / d; the box is the intersection of the three. A zero component
// of d makes 1/d infinite, and the slab is then all or nothing (the NaN of 0 * inf for a
// ray on the slab's plane is dropped by the min/max order below).
bool clip_ray_to_box(const CloudRay& ray, const glm::dvec3& lo, const glm::dvec3& hi, double& t_lo,
                     double& t_hi) {
    for (int a = 0; a < 3; ++a) {
        const double inv = 1.0 / ray.direction[a];
        double t0 = (lo[a] - ray.origin[a]) * inv, t1 = (hi[a] - ray.origin[a]) * inv;
        if (std::isnan(t0) || std::isnan(t1)) {
            if (ray.origin[a] < lo[a] || ray.origin[a] > hi[a]) return false;
            continue;
        }
        if (t0 > t1) std::swap(t0, t1);
        t_lo = std::max(t_lo, t0);
        t_hi = std::min(t_hi, t1);
        if (!(t_lo <= t_hi)) return false;
    }
    return true;
}

}  // namespace welkin
