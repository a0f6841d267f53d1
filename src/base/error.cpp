// SPDX-License-Identifier: Apache-2.0
#include "welkin/base/error.hpp"

#include <cmath>

#include <fmt/format.h>

namespace welkin {

void require_finite(const std::string& parameter, double value) {
    if (!std::isfinite(value))
        throw InvalidArgument(parameter, fmt::format("must be a finite number, got {}", value));
}

void require_in_range(const std::string& parameter, double value, double lo, double hi,
                      const std::string& unit) {
    if (!std::isfinite(value) || value < lo || value > hi) {
        const std::string u = unit.empty() ? "" : " " + unit;
        throw InvalidArgument(parameter, fmt::format("must be in [{}, {}]{}, got {}", lo, hi, u, value));
    }
}

}  // namespace welkin
