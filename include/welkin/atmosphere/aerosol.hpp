// SPDX-License-Identifier: Apache-2.0
// The aerosol as an artist or a meteorologist states it: its vertical optical depth at
// 550 nm, or a turbidity.
//
// The vertical aerosol optical depth at wavelength lambda is
//     tau(lambda) = beta_ext(lambda) int_0^top rho_M(h) dh,
// beta_ext the Mie extinction where the profile rho_M is 1 (atmosphere.hpp). At a
// wavelength between two channels it is interpolated in log tau against log lambda
// (Angstrom 1929's law, tau ~ lambda^-alpha, holds between them), beyond the channels
// extrapolated with the nearest two channels' exponent.
#pragma once

#include "welkin/atmosphere/atmosphere.hpp"

namespace welkin {

double aerosol_optical_depth(const Atmosphere& atm, double wavelength_nm = 550.0);

// Scales the aerosol's scattering and extinction (every channel alike, so its colour,
// albedo, phase and profile stay) so that aerosol_optical_depth(atm, 550) = tau_550.
// Throws InvalidArgument naming "aerosol_optical_depth" outside [0, 10], or when the
// atmosphere has no aerosol to scale (zero extinction) and tau_550 > 0.
void set_aerosol_optical_depth(Atmosphere& atm, double tau_550);

// Preetham, Shirley & Smits 1999, "A Practical Analytic Model for Daylight" (SIGGRAPH),
// Appendix A.2: turbidity T = (t_m + t_h) / t_m, with Angstrom's turbidity coefficient
// beta = 0.04608 T - 0.04586 and alpha = 1.3, tau_a(lambda) = beta (lambda / 1 um)^-alpha;
// so tau_550 = beta 0.55^-1.3. T in [1, 20] (InvalidArgument naming "turbidity" outside;
// T = 2 is a clear day, tau_550 = 0.10).
double preetham_turbidity_to_aerosol_optical_depth(double turbidity);

}  // namespace welkin
