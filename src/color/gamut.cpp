// SPDX-License-Identifier: Apache-2.0
// Gamut mapping at constant luminance toward the white point; see gamut.hpp.
#include "welkin/color/gamut.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace welkin {

std::array<double, 3> gamut_map(const std::array<double, 3>& c, const std::array<double, 3>& w) {
    const double lo = std::min({c[0], c[1], c[2]});
    if (lo >= 0.0 || !std::isfinite(c[0] + c[1] + c[2])) return c;  // in gamut, or for the caller
    const double y = w[0] * c[0] + w[1] * c[1] + w[2] * c[2];
    if (!(y > 0.0)) return {0.0, 0.0, 0.0};
    // rgb' = y + s (rgb - y) with the channel at `lo` brought to exactly 0.
    const double s = y / (y - lo);
    std::array<double, 3> out{};
    for (int k = 0; k < 3; ++k) out[k] = std::max(0.0, y + s * (c[k] - y));
    return out;
}

void gamut_map(float* rgb, std::size_t count, const std::array<double, 3>& w) {
    for (std::size_t i = 0; i < count; ++i) {
        float* p = rgb + 3 * i;
        if (p[0] >= 0.0f && p[1] >= 0.0f && p[2] >= 0.0f) continue;
        const std::array<double, 3> m = gamut_map({double(p[0]), double(p[1]), double(p[2])}, w);
        for (int k = 0; k < 3; ++k) p[k] = float(m[k]);
    }
}

}  // namespace welkin
