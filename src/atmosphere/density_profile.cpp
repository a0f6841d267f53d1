// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/density_profile.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {

double DensityLayer::density(double h) const {
    // (A layer without an exponential term, such as the ozone tent, skips the exp.)
    const double e = exp_term == 0.0 ? 0.0 : exp_term * std::exp(exp_scale_per_m * h);
    return std::clamp(e + linear_per_m * h + constant, 0.0, 1.0);
}

DensityProfile::DensityProfile(std::vector<DensityLayer> layers) : layers_(std::move(layers)) {}

DensityProfile DensityProfile::exponential(double scale_height_m) {
    if (!(scale_height_m > 0.0) || !std::isfinite(scale_height_m))
        throw InvalidArgument("scale_height_m", fmt::format("must be in (0, inf) m, got {}", scale_height_m));
    return DensityProfile({DensityLayer{0.0, 1.0, -1.0 / scale_height_m, 0.0, 0.0}});
}

DensityProfile DensityProfile::tent(double bottom_m, double peak_m, double top_m) {
    if (!(bottom_m < peak_m && peak_m < top_m))
        throw InvalidArgument(
            "tent", fmt::format("needs bottom < peak < top, got {}, {}, {} m", bottom_m, peak_m, top_m));
    const double up = 1.0 / (peak_m - bottom_m), down = 1.0 / (top_m - peak_m);
    return DensityProfile({DensityLayer{peak_m, 0.0, 0.0, up, -bottom_m * up},
                           DensityLayer{0.0, 0.0, 0.0, -down, top_m * down}});
}

DensityProfile DensityProfile::zero() { return DensityProfile({DensityLayer{}}); }

double DensityProfile::density(double h) const {
    double bottom = 0.0;
    for (std::size_t i = 0; i + 1 < layers_.size(); ++i) {
        bottom += layers_[i].width_m;
        if (h < bottom) return layers_[i].density(h);
    }
    return layers_.empty() ? 0.0 : layers_.back().density(h);
}

std::vector<double> DensityProfile::breakpoints_m() const {
    std::vector<double> points;
    double bottom = 0.0;
    for (std::size_t i = 0; i < layers_.size(); ++i) {
        const DensityLayer& l = layers_[i];
        const double top = i + 1 < layers_.size() ? bottom + l.width_m : 1e300;
        // Where a purely linear layer crosses 0 or 1, clamping starts: a kink.
        if (l.exp_term == 0.0 && l.linear_per_m != 0.0) {
            for (double level : {0.0, 1.0}) {
                const double h = (level - l.constant) / l.linear_per_m;
                if (h > bottom && h < top) points.push_back(h);
            }
        }
        if (i + 1 < layers_.size()) points.push_back(top);
        bottom = top;
    }
    std::sort(points.begin(), points.end());
    return points;
}

std::optional<double> DensityProfile::exponential_scale_height_m() const {
    if (layers_.size() != 1) return std::nullopt;
    const DensityLayer& l = layers_[0];
    if (l.exp_term == 1.0 && l.exp_scale_per_m < 0.0 && l.linear_per_m == 0.0 && l.constant == 0.0)
        return -1.0 / l.exp_scale_per_m;
    return std::nullopt;
}

void DensityProfile::validate(const std::string& parameter) const {
    if (layers_.empty())
        throw InvalidArgument(parameter,
                              "needs at least one layer (use a zero layer to switch "
                              "a constituent off)");
    if (layers_.size() > kMaxLayers)
        throw InvalidArgument(parameter + ".layers", fmt::format("must have between 1 and {} layers, got {}",
                                                                 kMaxLayers, layers_.size()));
    for (std::size_t i = 0; i < layers_.size(); ++i) {
        const DensityLayer& l = layers_[i];
        const std::string p = fmt::format("{}.layers[{}]", parameter, i);
        for (auto [name, v] :
             {std::pair{"exp_term", l.exp_term}, std::pair{"exp_scale_per_m", l.exp_scale_per_m},
              std::pair{"linear_per_m", l.linear_per_m}, std::pair{"constant", l.constant}})
            require_finite(p + "." + name, v);
        if (i + 1 < layers_.size() && !(l.width_m > 0.0 && std::isfinite(l.width_m)))
            throw InvalidArgument(p + ".width_m", fmt::format("must be in (0, inf) m, got {}", l.width_m));
    }
}

}  // namespace welkin
