// SPDX-License-Identifier: Apache-2.0
// The phase function of cloud droplets: two Henyey-Greenstein lobes, forward and back.
//
// Mie scattering by cloud droplets (radius ~5-10 um) has a strong forward peak (the silver
// lining), a weaker backward rise (glory, fogbow) and little in between. A blend of a
// forward and a backward Henyey-Greenstein lobe (Henyey & Greenstein 1941) captures that
// at the fidelity of a fast renderer: the standard choice in production cloud rendering
// (Hillaire 2016, "Physically based sky, atmosphere and cloud rendering in Frostbite",
// sec. 5.7; Schneider 2015). With nu the cosine between the light's propagation direction
// before and after scattering:
//     p(nu) = w HG(nu, g_forward) + (1 - w) HG(nu, g_back),
// normalised to 1 over the sphere, mean cosine w g_forward + (1 - w) g_back.
// Sampling picks a lobe with probability w, then inverts HG's cumulative distribution
// (atmosphere/phase_sampling.hpp, the reference sky's sampler).
#pragma once

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "welkin/atmosphere/phase.hpp"
#include "welkin/atmosphere/phase_sampling.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {

struct CloudPhase {
    double g_forward = 0.8;  // (-1, 1)
    double g_back = -0.3;    // (-1, 1)
    double w_forward = 0.8;  // [0, 1]

    void validate() const {
        require_in_range("g_forward", g_forward, -0.99, 0.99);
        require_in_range("g_back", g_back, -0.99, 0.99);
        require_in_range("w_forward", w_forward, 0.0, 1.0);
    }

    // p(nu), sr^-1; `g_scale` multiplies both eccentricities (Wrenninge's octaves).
    double operator()(double nu, double g_scale = 1.0) const {
        return w_forward * henyey_greenstein_phase(nu, g_forward * g_scale) +
               (1.0 - w_forward) * henyey_greenstein_phase(nu, g_back * g_scale);
    }
    double mean_cosine() const { return w_forward * g_forward + (1.0 - w_forward) * g_back; }

    // The angular distribution of light scattered twice, p convolved with itself over the
    // sphere (the path between the two events left out; clouds/diffusion.hpp). A phase's
    // Legendre moments multiply under this convolution (Funk-Hecke), and HG(g)'s moments
    // are g^l, so HG(g1) * HG(g2) = HG(g1 g2) and for the two lobes
    //     p2 = w^2 HG(g_f^2) + 2 w (1 - w) HG(g_f g_b) + (1 - w)^2 HG(g_b^2).
    double twice(double nu) const {
        const double w = w_forward;
        return w * w * henyey_greenstein_phase(nu, g_forward * g_forward) +
               2.0 * w * (1.0 - w) * henyey_greenstein_phase(nu, g_forward * g_back) +
               (1.0 - w) * (1.0 - w) * henyey_greenstein_phase(nu, g_back * g_back);
    }

    // A direction distributed as p(d . result) about the unit direction d; u0 picks the
    // lobe, (u1, u2) the direction, all uniform in [0, 1).
    glm::dvec3 sample(const glm::dvec3& d, double u0, double u1, double u2) const {
        const double g = u0 < w_forward ? g_forward : g_back;
        return direction_about(d, sample_henyey_greenstein_cosine(u1, g), u2);
    }
};

}  // namespace welkin
