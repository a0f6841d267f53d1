// SPDX-License-Identifier: Apache-2.0
// How the froxel aerial passes are compared with the per-pixel march, in the
// tests (which assert on it) and the benchmark (which reports it): over the non-sky pixels,
// the in-scattering relative to the march's value where that exceeds 1e-3 of the frame's
// largest (so that pixels a few metres away do not dominate by dividing by almost
// nothing), the transmittance absolute.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "welkin/aerial/aerial_perspective.hpp"

namespace welkin::test {

struct AerialComparison {
    double median_rel_L, p99_rel_L, max_rel_L, max_abs_T;
};

inline AerialComparison compare_aerial_passes(const AerialPasses& f, const AerialPasses& r,
                                              const std::vector<float>& depth) {
    float L_max = 0.0f;
    for (float v : r.inscatter) L_max = std::max(L_max, v);
    std::vector<double> rel;
    double max_T = 0.0;
    for (std::size_t p = 0; p < depth.size(); ++p) {
        if (!std::isfinite(depth[p])) continue;
        for (int c = 0; c < 3; ++c) {
            const double lr = r.inscatter[p * 3 + c], lf = f.inscatter[p * 3 + c];
            if (lr > 1e-3 * L_max) rel.push_back(std::abs(lf - lr) / lr);
            max_T =
                std::max(max_T, double(std::abs(f.transmittance[p * 3 + c] - r.transmittance[p * 3 + c])));
        }
    }
    if (rel.empty()) return {0.0, 0.0, 0.0, max_T};
    std::sort(rel.begin(), rel.end());
    return {rel[rel.size() / 2], rel[rel.size() * 99 / 100], rel.back(), max_T};
}

}  // namespace welkin::test
