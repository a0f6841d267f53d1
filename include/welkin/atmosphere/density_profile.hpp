// SPDX-License-Identifier: Apache-2.0
// Vertical density profiles of the atmosphere's constituents.
//
// A profile is a stack of layers, as in Bruneton 2017 (atmosphere/definitions.glsl,
// DensityProfileLayer): layer i covers altitudes [bottom_i, bottom_i + width_m) and has
//
//     rho(h) = exp_term * exp(exp_scale_per_m * h) + linear_per_m * h + constant,
//
// clamped to [0, 1]; the last layer extends upwards without limit. An exponential layer
// of scale height H is {exp_term = 1, exp_scale = -1/H}; the ozone tent (0 at 10 km,
// 1 at 25 km, 0 at 40 km) is two linear layers. Density is relative: the constituent's
// coefficients (m^-1) are their values where rho = 1.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace welkin {

struct DensityLayer {
    double width_m = 0.0;  // ignored for the last layer
    double exp_term = 0.0;
    double exp_scale_per_m = 0.0;
    double linear_per_m = 0.0;
    double constant = 0.0;

    double density(double altitude_m) const;

    bool operator==(const DensityLayer&) const = default;
};

class DensityProfile {
public:
    // The most layers a profile may have (docs/limits.md): the quadratures split their
    // intervals at every layer boundary, so the cost grows with the count.
    static constexpr std::size_t kMaxLayers = 32;

    DensityProfile() = default;
    explicit DensityProfile(std::vector<DensityLayer> layers);

    // rho(h) = exp(-h / H).
    static DensityProfile exponential(double scale_height_m);
    // Triangle rising linearly from 0 at `bottom_m` to 1 at `peak_m`, back to 0 at `top_m`.
    static DensityProfile tent(double bottom_m, double peak_m, double top_m);
    // rho = 0 everywhere: a constituent switched off.
    static DensityProfile zero();

    double density(double altitude_m) const;

    // Altitudes at which the profile's formula changes (layer boundaries, and the zero
    // crossings where clamping starts or stops): quadrature splits its intervals there.
    std::vector<double> breakpoints_m() const;

    // The scale height, when the profile is a single decaying exponential; else empty.
    std::optional<double> exponential_scale_height_m() const;

    const std::vector<DensityLayer>& layers() const { return layers_; }
    // Throws InvalidArgument naming `parameter` on non-finite terms, bad widths, or more
    // than kMaxLayers layers.
    void validate(const std::string& parameter) const;

    bool operator==(const DensityProfile&) const = default;

private:
    std::vector<DensityLayer> layers_;
};

}  // namespace welkin
