// SPDX-License-Identifier: Apache-2.0
// Single scattering for a row of the peer table by direct quadrature along the view ray,
// with exact (double-precision quadrature) transmittances: the trapezoid rule on
// `intervals` equal intervals, as Bruneton 2017's reference ComputeSingleScattering does
// with 50. Independent of every Welkin method.
#pragma once

#include <array>

#include "peer_table.hpp"

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/atmosphere/phase.hpp"

namespace welkin::test {

inline std::array<double, 3> single_scattering(const Atmosphere& atm, const PeerRow& row, int intervals) {
    const double R = atm.bottom_radius_m, top = atm.top_radius_m;
    const double r = R + row["alt_m"];
    const glm::dvec3 v = row.view_direction(), s = row.sun_direction();
    const double mu = v.z, mu_s = s.z, nu = v.x * s.x + v.y * s.y + v.z * s.z;
    const double d = distance_to_boundary(r, mu, R, top);
    const double dx = d / intervals;
    std::array<double, 3> sum{0.0, 0.0, 0.0};
    for (int i = 0; i <= intervals; ++i) {
        const double t = i * dx;
        const double r_t = radius_at(r, mu, t);
        const double mu_s_t = clamp_cosine((r * mu_s + t * nu) / r_t);
        const double h = r_t - R;
        if (ray_hits_ground(r_t, mu_s_t, R)) continue;  // the planet hides the sun
        const ColumnDensity view = column_density(atm, r, mu, t);
        const ColumnDensity sun = column_density(atm, r_t, mu_s_t, distance_to_top(r_t, mu_s_t, top));
        const double w = (i == 0 || i == intervals) ? 0.5 : 1.0;
        for (int c = 0; c < 3; ++c) {
            const double T = std::exp(-optical_depth(atm, c, view) - optical_depth(atm, c, sun));
            const double scattering =
                atm.rayleigh_scattering[c] * atm.rayleigh_density.density(h) * rayleigh_phase(nu) +
                atm.mie_scattering[c] * atm.mie_density.density(h) * mie_phase(atm.mie_phase, nu, atm.mie_g);
            sum[c] += w * T * scattering * dx * atm.solar_irradiance[c];
        }
    }
    return sum;
}

}  // namespace welkin::test
