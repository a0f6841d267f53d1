// SPDX-License-Identifier: Apache-2.0
// Direction sampling for the path tracers (the reference sky, the clouds' phase): phase
// functions and a Lambertian ground. Each sampler maps uniform numbers in [0, 1) to a cosine (or a direction)
// whose density is stated; tests/cpp/test_phase.cpp checks the distributions.
//
// Conventions as in phase.hpp: nu is the cosine between the two propagation directions;
// a path tracer that follows light backwards samples the next tracing direction w' from
// the current one w with cos(w, w') = nu distributed as 2 pi p(nu) (forward scattering
// keeps the tracing direction).
#pragma once

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "welkin/base/math.hpp"

namespace welkin {

// Rayleigh: density of nu is 2 pi * 3/(16 pi) (1 + nu^2) = 3/8 (1 + nu^2) on [-1, 1].
// CDF F(nu) = (nu^3 + 3 nu + 4) / 8; F(nu) = u is the depressed cubic
// nu^3 + 3 nu + (4 - 8u) = 0, whose one real root is (Cardano) nu = A - 1/A with
// A = cbrt(a + sqrt(a^2 + 1)), a = 4u - 2. For a < 0 we use the odd symmetry of the root
// in a, which keeps A away from the cancellation in a + sqrt(a^2 + 1).
inline double sample_rayleigh_cosine(double u) {
    const double a = 4.0 * u - 2.0;
    const double A = std::cbrt(std::abs(a) + std::sqrt(a * a + 1.0));
    const double nu = A - 1.0 / A;
    return clamp_cosine(a < 0.0 ? -nu : nu);
}

// Henyey-Greenstein: density of nu is 2 pi p_HG(nu, g). Inverting its CDF (e.g. pbrt-v4,
// SampleHenyeyGreenstein):
//     nu = (1 + g^2 - ((1 - g^2) / (1 + g - 2 g u))^2) / (2 g),
// uniform for |g| < 1e-3.
inline double sample_henyey_greenstein_cosine(double u, double g) {
    if (std::abs(g) < 1e-3) return clamp_cosine(1.0 - 2.0 * u);
    const double s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u);
    return clamp_cosine((1.0 + g * g - s * s) / (2.0 * g));
}

// An orthonormal basis around unit vector n (Duff et al. 2017, "Building an Orthonormal
// Basis, Revisited", JCGT 6(1)).
inline void orthonormal_basis(const glm::dvec3& n, glm::dvec3& t, glm::dvec3& b) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double c = n.x * n.y * a;
    t = glm::dvec3(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::dvec3(c, sign + n.y * n.y * a, -n.y);
}

// The unit vector at cosine `cos_theta` from unit vector `axis`, at azimuth 2 pi u about it.
inline glm::dvec3 direction_about(const glm::dvec3& axis, double cos_theta, double u) {
    glm::dvec3 t, b;
    orthonormal_basis(axis, t, b);
    const double sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    const double phi = kTwoPi * u;
    return glm::normalize(sin_theta * (std::cos(phi) * t + std::sin(phi) * b) + cos_theta * axis);
}

// Lambertian (cosine-weighted) hemisphere about the unit normal n: density cos / pi.
// cos theta = sqrt(u1) makes the projected point uniform on the unit disc (Malley).
inline glm::dvec3 sample_cosine_hemisphere(const glm::dvec3& n, double u1, double u2) {
    return direction_about(n, std::sqrt(u1), u2);
}

}  // namespace welkin
