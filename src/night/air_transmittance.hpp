// SPDX-License-Identifier: Apache-2.0
// The air's transmittance from the observer to the top of the atmosphere by elevation, for
// the night layer's point and diffuse sources (stars.cpp, night_glow.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/math.hpp"

namespace welkin::night {

// The air's transmittance to the top along elevation e, tabulated once per image on a grid
// dense near the horizon (e = e_h + (90 deg - e_h) (k / N)^2, e_h the horizon's
// elevation) as optical depth, interpolated linearly (the optical depth follows the air
// mass, smooth in e where the transmittance itself is not); 0 below the horizon.
class TransmittanceByElevation {
public:
    TransmittanceByElevation(const Atmosphere& atm, double altitude_m)
        : r_(atm.bottom_radius_m + altitude_m), bottom_(atm.bottom_radius_m), nc_(atm.channels()) {
        const double mu_h = r_ > bottom_ ? -std::sqrt(r_ * r_ - bottom_ * bottom_) / r_ : 0.0;
        e_h_ = std::asin(mu_h);
        table_.resize((kN + 1) * nc_);
        for (int k = 0; k <= kN; ++k) {
            const double t = double(k) / kN;
            // Just above the horizon: a ray exactly grazing it is ill-defined.
            const double e = e_h_ + (0.5 * kPi - e_h_) * std::max(t * t, 1e-6);
            const std::vector<double> tr = transmittance_to_boundary(atm, r_, std::sin(e));
            for (std::size_t c = 0; c < nc_; ++c)
                table_[std::size_t(k) * nc_ + c] = -std::log(std::max(tr[c], 1e-300));
        }
    }
    // Per channel into out; false when the direction is behind the ground.
    bool operator()(double sin_elevation, std::vector<double>& out) const {
        if (ray_hits_ground(r_, sin_elevation, bottom_)) return false;
        const double e = std::asin(clamp_cosine(sin_elevation));
        const double x = kN * std::sqrt(std::max(0.0, (e - e_h_) / (0.5 * kPi - e_h_)));
        const int k = std::clamp(int(x), 0, kN - 1);
        const double f = std::clamp(x - k, 0.0, 1.0);
        for (std::size_t c = 0; c < nc_; ++c)
            out[c] = std::exp(
                -(table_[std::size_t(k) * nc_ + c] * (1.0 - f) + table_[std::size_t(k + 1) * nc_ + c] * f));
        return true;
    }

private:
    static constexpr int kN = 256;
    double r_, bottom_, e_h_ = 0.0;
    std::size_t nc_;
    std::vector<double> table_;
};

}  // namespace welkin::night
