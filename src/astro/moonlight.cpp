// SPDX-License-Identifier: Apache-2.0
// Moonlight at the top of the atmosphere (include/welkin/astro/moonlight.hpp).
#include "welkin/astro/moonlight.hpp"

#include <algorithm>
#include <cmath>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {
namespace {

constexpr double kMoonMeanDistance_m = 384400e3;  // Allen's reference distance
constexpr double kAu_m = 149597870.7e3;
constexpr double kSunV = -26.74;  // the Sun's V magnitude at 1 au (Allen)

}  // namespace

double moon_v_magnitude(double alpha) {
    require_in_range("phase_angle_deg", alpha, 0.0, 180.0, "degrees");
    return -12.73 + 0.026 * alpha + 4e-9 * alpha * alpha * alpha * alpha;
}

double moon_irradiance_ratio(double phase_angle_deg, double moon_distance_m, double sun_distance_m) {
    require_in_range("moon_distance_m", moon_distance_m, 1e8, 1e9, "m");
    require_in_range("sun_distance_m", sun_distance_m, 1e11, 2e11, "m");
    const double d = kMoonMeanDistance_m / moon_distance_m, s = kAu_m / sun_distance_m;
    return std::pow(10.0, -0.4 * (moon_v_magnitude(phase_angle_deg) - kSunV)) * d * d * s * s;
}

double moon_disc_relative_radiance(const std::array<double, 3>& v, const std::array<double, 3>& m,
                                   double radius_rad, const std::array<double, 3>& s) {
    // The moon a unit sphere at distance D = 1 / sin(radius) along m; the view ray t v
    // meets it where t^2 - 2 t D (v.m) + D^2 - 1 = 0 (the nearer root).
    const double D = 1.0 / std::sin(radius_rad);
    const double vm = v[0] * m[0] + v[1] * m[1] + v[2] * m[2];
    const double disc = D * D * vm * vm - D * D + 1.0;
    if (disc <= 0.0 || vm <= 0.0) return 0.0;
    const double t = D * vm - std::sqrt(disc);
    const std::array<double, 3> n{t * v[0] - D * m[0], t * v[1] - D * m[1], t * v[2] - D * m[2]};
    const double mu = -(n[0] * v[0] + n[1] * v[1] + n[2] * v[2]);  // towards the observer
    const double mu0 = n[0] * s[0] + n[1] * s[1] + n[2] * s[2];    // towards the sun
    if (mu0 <= 0.0 || mu <= 0.0) return 0.0;
    return mu0 / (mu0 + mu);
}

double moon_disc_relative_radiance_far(const std::array<double, 3>& v, const std::array<double, 3>& m,
                                       double radius_rad, const std::array<double, 3>& s) {
    const auto cross = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                     a[0] * b[1] - a[1] * b[0]};
    };
    const auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    };
    const double sin_alpha = std::sin(radius_rad);
    const std::array<double, 3> vm = cross(v, m), sm = cross(s, m);
    const double x = std::sqrt(dot(vm, vm)) / sin_alpha;
    if (!(x < 1.0) || dot(v, m) <= 0.0) return 0.0;
    const double mu = std::sqrt(1.0 - x * x);
    const double mu0 = dot(vm, sm) / sin_alpha - mu * dot(m, s);
    if (mu0 <= 0.0) return 0.0;
    return mu0 / (mu0 + mu);
}

double moon_disc_relative_integral_far(double g, double radius_rad) {
    if (!(radius_rad > 0.0 && radius_rad <= 0.05))
        throw InvalidArgument("radius_rad", "must be in (0, 0.05] rad");
    if (!std::isfinite(g)) throw InvalidArgument("phase_angle_rad", "must be finite");
    g = std::clamp(std::abs(g), 0.0, kPi);
    const double sin_a = std::sin(radius_rad);
    double phi = 1.0;
    if (g >= kPi) {
        phi = 0.0;
    } else if (g > 0.0) {
        // ln cot(g/4) -> infinity as g -> 0, but sin(g/2) tan(g/2) -> 0 faster.
        phi = 1.0 - std::sin(0.5 * g) * std::tan(0.5 * g) * std::log(1.0 / std::tan(0.25 * g));
    }
    return sin_a * sin_a * 0.5 * kPi * std::max(0.0, phi);
}

}  // namespace welkin
