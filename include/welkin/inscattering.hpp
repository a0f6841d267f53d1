// The single-scattering march shared by the sky-view LUT and the ray-march method.
//
// Along a view ray from radius r with zenith cosine mu, the path radiance is
// (Hillaire 2020 eqs. 1-4, 10)
//
//   L = integral_0^d T(0, t) J(t) dt,
//   J = E_sun [ T_sun(t) (sigma_R P_R(nu) + sigma_M P_M(nu)) + (sigma_R + sigma_M) Psi_ms(t) ],
//
// with the sun's zenith cosine at distance t, mu_s(t) = (r mu_s + t nu) / r(t) (Bruneton
// 2017, eq. for mu_s_d). Samples are spread as t = d s^2 for s uniform in [0, 1]: dense
// near the observer, where an upward ray is densest and where a near-horizontal ray from
// low altitude spends its first kilometres; each segment is integrated with Hillaire's
// energy-conserving form: with S the source at the segment's midpoint (in s) and
// T_seg = exp(-sigma_t dt), the segment adds T (S - S T_seg) / sigma_t (Hillaire 2015,
// "Physically Based and Unified Volumetric Rendering in Frostbite"), which stays right
// however thick a segment is.
//
// An observer above the atmosphere is first moved to where the ray enters it; rays that
// miss the atmosphere see nothing.
#pragma once

#include <cmath>

#include "welkin/geometry.hpp"
#include "welkin/multiscattering_lut.hpp"

namespace welkin {

struct InscatterResult {
    Spectrum4 radiance{0.0f};       // W m^-2 sr^-1 nm^-1
    Spectrum4 transmittance{1.0f};  // along the whole path
};

// SunTransmittance: callable (double r, double mu_s) -> Spectrum4, the sun's transmittance
// (with the planet's shadow) at a point.
template <class SunTransmittance>
InscatterResult integrate_inscattering(const AtmosphereBatch& batch, const MultiScatteringLut* ms,
                                       double r, double mu, double mu_s, double nu, int steps,
                                       SunTransmittance&& sun_transmittance) {
    InscatterResult result;
    const double R = batch.bottom_radius(), top = batch.top_radius();
    if (r > top) {
        const double entry = distance_to_atmosphere_entry(r, mu, top);
        if (entry < 0.0) return result;
        const double r_entry = std::min(radius_at(r, mu, entry), top);
        mu_s = clamp_cosine((r * mu_s + entry * nu) / r_entry);
        mu = mu_at(r, mu, entry, r_entry);
        r = r_entry;
    }
    const double d = distance_to_boundary(r, mu, R, top);
    const float rayleigh_p = batch.rayleigh_phase(float(nu));
    const float mie_p = batch.mie_phase(float(nu));
    Spectrum4 T(1.0f), L(0.0f);
    const double inv_n = 1.0 / double(steps);
    for (int i = 0; i < steps; ++i) {
        const double s0 = double(i) * inv_n, s1 = double(i + 1) * inv_n, sm = (double(i) + 0.5) * inv_n;
        const double dt = d * (s1 * s1 - s0 * s0);
        const double t = d * sm * sm;
        const double r_t = radius_at(r, mu, t);
        const double mu_s_t = clamp_cosine((r * mu_s + t * nu) / r_t);
        const MediumSample m = batch.sample(r_t - R);
        const Spectrum4 scattering = m.rayleigh_scattering + m.mie_scattering;
        Spectrum4 source = sun_transmittance(r_t, mu_s_t) *
                           (m.rayleigh_scattering * rayleigh_p + m.mie_scattering * mie_p);
        if (ms) source += scattering * ms->psi(r_t, mu_s_t);
        const Spectrum4 T_seg = glm::exp(-m.extinction * float(dt));
        for (int c = 0; c < 4; ++c) {
            const float integral = m.extinction[c] > 1e-12f ? (1.0f - T_seg[c]) / m.extinction[c] : float(dt);
            L[c] += T[c] * source[c] * integral;
        }
        T *= T_seg;
    }
    result.radiance = L * batch.solar_irradiance();
    result.transmittance = T;
    return result;
}

}  // namespace welkin
