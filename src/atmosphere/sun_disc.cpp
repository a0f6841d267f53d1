// The sun's disc as a radiance distribution; see sun_disc.hpp.
#include "welkin/atmosphere/sun_disc.hpp"

#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

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

SunDisc::Rgb SunDisc::rgb(std::span<const double> m) const {
    const std::size_t n = channels();
    if (m.size() != 3 * n)
        throw InvalidArgument("to_rgb", fmt::format("must hold 3 x {} values, got {}", n, m.size()));
    const std::vector<double> centre = centre_radiance();
    Rgb out;
    for (int j = 0; j < 3; ++j) {
        double lc = 0.0;
        std::array<double, 6> b{};
        for (std::size_t c = 0; c < n; ++c) {
            const double w = m[std::size_t(j) * n + c] * centre[c];
            lc += w;
            for (int k = 0; k < 6; ++k) b[k] += w * coefficients_[c][k];
        }
        out.centre_radiance[j] = lc;
        // A channel with no light keeps the coefficients' plain mean shape (any polynomial
        // times 0 is 0); otherwise b / L_centre (header).
        for (int k = 0; k < 6; ++k) {
            double mean_a = 0.0;
            for (std::size_t c = 0; c < n; ++c) mean_a += coefficients_[c][k] / double(n);
            out.limb_coefficients[j][k] = lc != 0.0 ? b[k] / lc : mean_a;
        }
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
