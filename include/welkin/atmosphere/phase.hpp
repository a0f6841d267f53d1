// SPDX-License-Identifier: Apache-2.0
// Phase functions, normalised so that they integrate to 1 over the sphere (sr^-1).
//
// nu is the cosine of the scattering angle between the propagation directions: nu = 1
// is forward scattering. For a sky seen from the observer with view direction v (towards
// the sky) and sun direction s (towards the sun), light travels from s's side to the
// observer, so nu = dot(v, s) (Bruneton 2017, definitions of nu).
#pragma once

#include <cmath>

#include "welkin/base/math.hpp"

namespace welkin {

enum class MiePhaseModel { HenyeyGreenstein, CornetteShanks };

// Rayleigh: 3 / (16 pi) (1 + nu^2).
template <class T>
inline T rayleigh_phase(T nu) {
    return T(3.0 / (16.0 * kPi)) * (T(1) + nu * nu);
}

// Henyey-Greenstein 1941: (1 - g^2) / (4 pi (1 + g^2 - 2 g nu)^{3/2}).
template <class T>
inline T henyey_greenstein_phase(T nu, T g) {
    const T denom = T(1) + g * g - T(2) * g * nu;
    return (T(1) - g * g) / (T(4.0 * kPi) * denom * std::sqrt(denom));
}

// Cornette & Shanks 1992, "Physically reasonable analytic expression for the
// single-scattering phase function", Appl. Opt. 31(16), eq. 4, as used by Bruneton 2017:
// 3/(8 pi) (1 - g^2)(1 + nu^2) / ((2 + g^2)(1 + g^2 - 2 g nu)^{3/2}).
template <class T>
inline T cornette_shanks_phase(T nu, T g) {
    const T k = T(3.0 / (8.0 * kPi)) * (T(1) - g * g) / (T(2) + g * g);
    const T denom = T(1) + g * g - T(2) * g * nu;
    return k * (T(1) + nu * nu) / (denom * std::sqrt(denom));
}

template <class T>
inline T mie_phase(MiePhaseModel model, T nu, T g) {
    return model == MiePhaseModel::HenyeyGreenstein ? henyey_greenstein_phase(nu, g)
                                                    : cornette_shanks_phase(nu, g);
}

inline constexpr double kIsotropicPhase = 1.0 / (4.0 * kPi);

// Legendre moments chi_l = 2 pi int_-1^1 p(nu) P_l(nu) dnu of the phase functions, l = 0, 1, 2
// (chi_0 = 1 for every normalised phase), so that p(nu) = sum_l (2l + 1) / (4 pi) chi_l P_l(nu).
// By the Funk-Hecke theorem, int_S2 p(w . v) Y_l(w) dw = chi_l Y_l(v) for any spherical
// harmonic Y_l of degree l: a phase function scatters each degree of a radiance field with
// its own weight (the multiple-scattering LUT uses this, multiscattering_lut.hpp).
//   Rayleigh: 3/4 (1 + nu^2) = 1 + P_2 / 2 in units of 1 / (4 pi), so chi = (1, 0, 1/10).
//   Henyey-Greenstein: chi_l = g^l (its generating function).
//   Cornette-Shanks = HG times 3 (1 + nu^2) / (2 (2 + g^2)); with nu^3 = (3 P_1 + 2 P_3) / 5
//   and nu^2 P_2 = 2/15 + 11/21 P_2 + 12/35 P_4 the HG moments give
//     chi_1 = 3 g (4 + g^2) / (5 (2 + g^2)),
//     chi_2 = 3 (2/15 + 32/21 g^2 + 12/35 g^4) / (2 (2 + g^2))   (0.1 at g = 0, Rayleigh's).
inline double rayleigh_phase_moment(int l) { return l == 0 ? 1.0 : l == 2 ? 0.1 : 0.0; }
inline double mie_phase_moment(MiePhaseModel model, int l, double g) {
    if (l == 0) return 1.0;
    if (model == MiePhaseModel::HenyeyGreenstein) return l == 1 ? g : g * g;
    const double g2 = g * g;
    return l == 1 ? 3.0 * g * (4.0 + g2) / (5.0 * (2.0 + g2))
                  : 3.0 * (2.0 / 15.0 + 32.0 / 21.0 * g2 + 12.0 / 35.0 * g2 * g2) / (2.0 * (2.0 + g2));
}

}  // namespace welkin
