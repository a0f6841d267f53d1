// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/observer.hpp"

#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"

namespace welkin {

Observer Observer::validated() const {
    // 1e9 m: far beyond any atmosphere; the sky from there is a dot.
    require_in_range("altitude_m", altitude_m, 0.0, 1e9, "m");
    const double len = glm::length(sun_direction);
    if (!std::isfinite(len) || !(len > 1e-12))
        throw InvalidArgument("sun_direction",
                              fmt::format("must be a finite non-zero vector, "
                                          "got ({}, {}, {})",
                                          sun_direction.x, sun_direction.y, sun_direction.z));
    Observer o = *this;
    o.sun_direction = sun_direction / len;
    return o;
}

void validate_directions(std::span<const glm::dvec3> directions) {
    for (std::size_t i = 0; i < directions.size(); ++i) {
        const glm::dvec3& d = directions[i];
        const double len2 = glm::dot(d, d);
        if (!std::isfinite(len2) || !(len2 > 1e-24))
            throw InvalidArgument(
                fmt::format("view_directions[{}]", i),
                fmt::format("must be a finite non-zero vector, got ({}, {}, {})", d.x, d.y, d.z));
    }
}

}  // namespace welkin
