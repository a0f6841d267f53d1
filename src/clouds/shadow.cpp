// SPDX-License-Identifier: Apache-2.0
// The clouds' transmittance towards a distant light: see shadow.hpp.
#include "welkin/clouds/shadow.hpp"

#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/depth_grid.hpp"

namespace welkin {

void CloudShadowOptions::validate() const {
    if (!(steps >= 1 && steps <= 65536)) throw InvalidArgument("steps", "must be in [1, 65536]");
    if (!(max_distance_m > 0.0 && std::isfinite(max_distance_m)))
        throw InvalidArgument("max_distance_m", "must be finite and > 0");
}

std::vector<float> cloud_transmittance(const CloudDensity& density, std::span<const glm::dvec3> points,
                                       const glm::dvec3& direction, const CloudShadowOptions& options,
                                       Progress* progress) {
    options.validate();
    const double length = glm::length(direction);
    if (!(length > 0.0 && std::isfinite(length)))
        throw InvalidArgument("direction", "must be a finite, non-zero vector towards the light");
    const glm::dvec3 w = direction / length;
    for (const glm::dvec3& p : points)
        if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
            throw InvalidArgument("points", "must be finite");
    std::vector<float> out(points.size(), 1.0f);
    ProgressTracker tracker(progress, points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 64), [&](const auto& range) {
        std::vector<MajorantSegment> segs;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const CloudRay ray{points[i], w};
            out[i] = float(
                std::exp(-march_optical_depth(density, ray, options.max_distance_m, options.steps, segs)));
        }
        tracker.advance(range.size());
    });
    tracker.finish();
    return out;
}

}  // namespace welkin
