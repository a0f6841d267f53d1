// SPDX-License-Identifier: Apache-2.0
// Aerosol optical depth and turbidity; see aerosol.hpp.
#include "welkin/atmosphere/aerosol.hpp"

#include <algorithm>
#include <cmath>

#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/error.hpp"

namespace welkin {
namespace {

// int_0^top rho_M(h) dh along the vertical, m.
double aerosol_column_m(const Atmosphere& atm) {
    return density_integral(atm.mie_density, atm.bottom_radius_m, atm.bottom_radius_m, 1.0,
                            atm.atmosphere_thickness_m());
}

}  // namespace

double aerosol_optical_depth(const Atmosphere& atm, double wavelength_nm) {
    atm.validate();
    require_in_range("wavelength_nm", wavelength_nm, 1.0, 1e5, "nm");
    const double column = aerosol_column_m(atm);
    const std::size_t n = atm.channels();
    if (n == 1) return atm.mie_extinction[0] * column;
    // The two channels that bracket the wavelength (or the nearest two beyond the ends).
    std::vector<std::size_t> order(n);
    for (std::size_t c = 0; c < n; ++c) order[c] = c;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return atm.wavelengths_nm[a] < atm.wavelengths_nm[b]; });
    std::size_t k = 1;
    while (k + 1 < n && atm.wavelengths_nm[order[k]] < wavelength_nm) ++k;
    const double l0 = atm.wavelengths_nm[order[k - 1]], l1 = atm.wavelengths_nm[order[k]];
    const double t0 = atm.mie_extinction[order[k - 1]] * column, t1 = atm.mie_extinction[order[k]] * column;
    if (!(t0 > 0.0) || !(t1 > 0.0)) {  // no power law through a zero: linear, clamped at 0
        const double f = (wavelength_nm - l0) / (l1 - l0);
        return std::max(0.0, t0 + f * (t1 - t0));
    }
    const double alpha = -std::log(t1 / t0) / std::log(l1 / l0);
    return t0 * std::pow(wavelength_nm / l0, -alpha);
}

void set_aerosol_optical_depth(Atmosphere& atm, double tau_550) {
    require_in_range("aerosol_optical_depth", tau_550, 0.0, 10.0);
    const double now = aerosol_optical_depth(atm, 550.0);
    if (!(now > 0.0)) {
        if (tau_550 == 0.0) return;
        throw InvalidArgument("aerosol_optical_depth",
                              "the atmosphere has no aerosol extinction to scale; set its mie "
                              "coefficients first");
    }
    const double s = tau_550 / now;
    for (double& v : atm.mie_extinction) v *= s;
    for (double& v : atm.mie_scattering) v *= s;
}

double preetham_turbidity_to_aerosol_optical_depth(double turbidity) {
    require_in_range("turbidity", turbidity, 1.0, 20.0);
    const double beta = 0.04608 * turbidity - 0.04586;
    return beta * std::pow(0.55, -1.3);
}

}  // namespace welkin
