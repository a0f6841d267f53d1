// Phase functions, normalised so that they integrate to 1 over the sphere (sr^-1).
//
// nu is the cosine of the scattering angle between the propagation directions: nu = 1
// is forward scattering. For a sky seen from the observer with view direction v (towards
// the sky) and sun direction s (towards the sun), light travels from s's side to the
// observer, so nu = dot(v, s) (Bruneton 2017, definitions of nu).
#pragma once

#include <cmath>

#include "welkin/math.hpp"

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

}  // namespace welkin
