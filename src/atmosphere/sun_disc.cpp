// SPDX-License-Identifier: Apache-2.0
// The sun's disc as a radiance distribution; see sun_disc.hpp.
#include "welkin/atmosphere/sun_disc.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/gamut.hpp"

namespace welkin {

SunDisc::SunDisc(const Atmosphere& atm, const Observer& observer)
    : alpha_(atm.sun_angular_radius_rad),
      omega_(kTwoPi * (1.0 - std::cos(atm.sun_angular_radius_rad))),
      direction_(observer.validated().sun_direction),
      sun_(sun_radiometry(atm, observer)) {
    const std::size_t n = atm.channels();
    mean_.assign(n, 0.0);
    for (std::size_t c = 0; c < n; ++c) {
        limb_.emplace_back(alpha_, atm.wavelengths_nm[c]);
        coefficients_.push_back(limb_darkening_coefficients(atm.wavelengths_nm[c]));
        if (sun_.visible_fraction > 0.0)
            mean_[c] = sun_.direct_irradiance[c] / (sun_.visible_fraction * omega_);
    }
}

std::vector<double> SunDisc::centre_radiance() const {
    std::vector<double> out(mean_.size());
    for (std::size_t c = 0; c < mean_.size(); ++c) out[c] = mean_[c] * limb_[c].centre();
    return out;
}

SunDisc::Rgb SunDisc::rgb(std::span<const double> m, const std::array<double, 3>& luminance) const {
    const std::size_t n = channels();
    if (m.size() != 3 * n)
        throw InvalidArgument("to_rgb", fmt::format("must hold 3 x {} values, got {}", n, m.size()));
    const std::vector<double> centre = centre_radiance();
    // The disc's mean colour, M L_mean, in the output gamut (gamut.hpp): its integral over
    // the disc is then the lamp's colour, gamut_map(M E_dir) / Omega.
    std::array<double, 3> mean_rgb{};
    for (int j = 0; j < 3; ++j)
        for (std::size_t c = 0; c < n; ++c) mean_rgb[j] += m[std::size_t(j) * n + c] * mean_[c];
    mean_rgb = gamut_map(mean_rgb, luminance);
    Rgb out;
    for (int j = 0; j < 3; ++j) {
        // Weights w_c of the channel's limb shape (header): M_jc L_centre,c where positive.
        std::vector<double> w(n, 0.0);
        double total = 0.0;
        for (std::size_t c = 0; c < n; ++c) {
            w[c] = std::max(0.0, m[std::size_t(j) * n + c] * centre[c]);
            total += w[c];
        }
        if (!(total > 0.0)) {  // no light at all: the plain mean shape
            std::fill(w.begin(), w.end(), 1.0);
            total = double(n);
        }
        // b_k = sum_c w_c a_k,c / sum_c w_c; mean of its polynomial over the disc / L_centre
        // = sum_c w_c (L_mean,c / L_centre,c) / sum_c w_c.
        std::array<double, 6> b{};
        double mean_over_centre = 0.0;
        for (std::size_t c = 0; c < n; ++c) {
            for (int k = 0; k < 6; ++k) b[k] += w[c] / total * coefficients_[c][k];
            mean_over_centre += w[c] / total / limb_[c].centre();
        }
        out.limb_coefficients[j] = b;
        out.centre_radiance[j] = mean_rgb[j] / mean_over_centre;
    }
    return out;
}

double SunDisc::angle_to(const glm::dvec3& d) const {
    return std::atan2(glm::length(glm::cross(d, direction_)), glm::dot(d, direction_));
}

bool SunDisc::add_radiance(double rho, double weight, std::span<double> out) const {
    if (!(rho <= alpha_)) return false;
    for (std::size_t c = 0; c < mean_.size(); ++c) out[c] += weight * mean_[c] * limb_[c](rho);
    return true;
}

}  // namespace welkin
