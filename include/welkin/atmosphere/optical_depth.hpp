// SPDX-License-Identifier: Apache-2.0
// Optical depth and transmittance by accurate quadrature, in double precision.
//
// These are the slow, exact answers the reference path tracer and the sun radiometry use,
// and against which the transmittance LUT is tested. The integral of a density profile
// along a straight ray is split at every altitude where the profile changes formula (and
// at the ray's lowest point), and each piece is integrated by composite Gauss-Legendre on
// panels graded towards the low end, where exponential layers change fastest. For an
// exponential layer along a vertical ray the result matches the closed form
// H (exp(-h0/H) - exp(-h1/H)) to about 1e-9 relative.
#pragma once

#include <vector>

#include "welkin/atmosphere/atmosphere.hpp"

namespace welkin {

// Integral of profile density (dimensionless) along the ray from radius r, zenith cosine
// mu, over [0, length_m]; result in metres.
double density_integral(const DensityProfile& profile, double bottom_radius_m, double r, double mu,
                        double length_m);

// Column integrals of the three constituents along a ray.
struct ColumnDensity {
    double rayleigh_m, mie_m, absorption_m;
};
ColumnDensity column_density(const Atmosphere& atm, double r, double mu, double length_m);

// Optical depth of channel c for a column.
double optical_depth(const Atmosphere& atm, std::size_t c, const ColumnDensity& column);

// Transmittance of every channel from radius r along mu to the atmosphere's boundary
// (0 for rays that hit the ground when `ground_blocks`).
std::vector<double> transmittance_to_boundary(const Atmosphere& atm, double r, double mu,
                                              bool ground_blocks = true);

}  // namespace welkin
