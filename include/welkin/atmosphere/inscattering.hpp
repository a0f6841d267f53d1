// SPDX-License-Identifier: Apache-2.0
// The single-scattering march shared by the sky-view LUT and the ray-march method.
//
// Along a view ray from radius r with zenith cosine mu, the path radiance is
// (Hillaire 2020 eqs. 1-4, 10)
//
//   L = integral_0^d T(0, t) J(t) dt,
//   J = E_sun [ T_sun(t) (sigma_R P_R(nu) + sigma_M P_M(nu)) + J_ms(t) ],
//
// with the sun's zenith cosine at distance t, mu_s(t) = (r mu_s + t nu) / r(t) (Bruneton
// 2017, eq. for mu_s_d), and J_ms the multiple-scattering source of multiscattering_lut.hpp:
// Hillaire's (sigma_R + sigma_M) Psi_ms plus the terms of the multiply-scattered light's
// dipole and quadrupole about the local zenith, weighted by the view's zenith cosine
// there, mu_v(t) = (r mu + t) / r(t) (view_zenith_cosine below). Samples are spread as t = d s^2 for s
// uniform in [0, 1]: dense near the observer, where an upward ray is densest and where a near-horizontal ray
// from low altitude spends its first kilometres; each segment is integrated with Hillaire's energy-conserving
// form: with S the source at the segment's midpoint (in s) and T_seg = exp(-sigma_t dt), the segment adds T
// (S - S T_seg) / sigma_t (Hillaire 2015, "Physically Based and Unified Volumetric Rendering in Frostbite"),
// which stays right however thick a segment is.
//
// The march is split in two because everything but the sun depends on the ray alone:
// RaySamples holds, per step, the radius, the scattering coefficients and the weight
// T (1 - T_seg) / sigma_t; inscatter() then adds the sun- and phase-dependent source for
// any (mu_s, nu). The sky-view LUT prepares one RaySamples per row (a view zenith angle)
// and reuses it for every azimuth in the row, through inscatter_row(), the same sum
// arranged for many nu at once.
//
// An observer above the atmosphere is first moved to where the ray enters it; rays that
// miss the atmosphere, and rays of no length (from the ground, below its horizon), see nothing.
#pragma once

#include <cmath>
#include <span>
#include <vector>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/multiscattering_lut.hpp"

namespace welkin {

struct RaySamples {
    struct Step {
        double t;          // distance from the observer (not from the atmosphere entry)
        double r;          // radius of the sample
        Spectrum4 weight;  // T(0, t_start) (1 - T_seg) / sigma_t, metres
        Spectrum4 rayleigh_scattering, mie_scattering;
        TransmittanceLut::AtRadius sun_at;  // filled when prepared with a transmittance LUT
        float ms_v = 0.0f;
    };
    double r0 = 0.0;   // the observer's radius
    double mu0 = 1.0;  // the view's zenith cosine at the observer
    std::vector<Step> steps;
    Spectrum4 transmittance{1.0f};  // along the whole path
};

// Fills `out` for the ray (r, mu). `tlut` and `ms`, if given, also precompute the
// radius-only parts of their lookups.
inline void prepare_ray(const AtmosphereBatch& batch, double r, double mu, int steps, RaySamples& out,
                        const TransmittanceLut* tlut = nullptr, const MultiScatteringLut* ms = nullptr) {
    out.steps.clear();
    out.r0 = r;
    out.mu0 = mu;
    out.transmittance = Spectrum4(1.0f);
    const double R = batch.bottom_radius(), top = batch.top_radius();
    double offset = 0.0;
    if (r > top) {
        offset = distance_to_atmosphere_entry(r, mu, top);
        if (offset < 0.0) return;
        const double r_entry = std::min(radius_at(r, mu, offset), top);
        mu = mu_at(r, mu, offset, r_entry);
        r = r_entry;
    }
    const double d = distance_to_boundary(r, mu, R, top);
    // A ray of no length (looking below the horizon from the ground itself, as half of a
    // ground-level sky-view LUT does) crosses no air: no steps, rather than steps of
    // weight zero.
    if (!(d > 0.0)) return;
    out.steps.resize(std::size_t(steps));
    Spectrum4 T(1.0f);
    const double inv_n = 1.0 / double(steps);
    for (int i = 0; i < steps; ++i) {
        const double s0 = double(i) * inv_n, s1 = double(i + 1) * inv_n, sm = (double(i) + 0.5) * inv_n;
        const double dt = d * (s1 * s1 - s0 * s0);
        const double t = d * sm * sm;
        RaySamples::Step& st = out.steps[std::size_t(i)];
        st.t = offset + t;
        st.r = radius_at(r, mu, t);
        const MediumSample m = batch.sample(st.r - R);
        st.rayleigh_scattering = m.rayleigh_scattering;
        st.mie_scattering = m.mie_scattering;
        const Spectrum4 T_seg = glm::exp(-m.extinction * float(dt));
        for (int c = 0; c < 4; ++c)
            st.weight[c] =
                T[c] * (m.extinction[c] > 1e-12f ? (1.0f - T_seg[c]) / m.extinction[c] : float(dt));
        if (tlut) st.sun_at = tlut->at_radius(st.r);
        if (ms) st.ms_v = ms->v_at_radius(st.r);
        T *= T_seg;
    }
    out.transmittance = T;
}

// The view's zenith cosine at a step: the local zenith turns along the ray, so a view that
// leaves the observer horizontally climbs through the air at mu_v = t / r(t).
inline double view_zenith_cosine(const RaySamples& ray, const RaySamples::Step& st) {
    return clamp_cosine((ray.r0 * ray.mu0 + st.t) / st.r);
}

// Path radiance of a prepared ray for the sun at zenith cosine mu_s (at the observer) and
// view-sun cosine nu. SunTransmittance: callable (const RaySamples::Step&, double mu_s_t)
// -> Spectrum4, the sun's transmittance (with the planet's shadow) at a step.
template <class SunTransmittance>
Spectrum4 inscatter(const AtmosphereBatch& batch, const MultiScatteringLut* ms, const RaySamples& ray,
                    double mu_s, double nu, SunTransmittance&& sun_transmittance) {
    const float rayleigh_p = batch.rayleigh_phase(float(nu));
    const float mie_p = batch.mie_phase(float(nu));
    Spectrum4 L(0.0f);
    for (const RaySamples::Step& st : ray.steps) {
        const double mu_s_t = clamp_cosine((ray.r0 * mu_s + st.t * nu) / st.r);
        Spectrum4 source =
            sun_transmittance(st, mu_s_t) * (st.rayleigh_scattering * rayleigh_p + st.mie_scattering * mie_p);
        if (ms) {
            Spectrum4 w1, w2;
            ms->source_weights(st.rayleigh_scattering, st.mie_scattering, view_zenith_cosine(ray, st), w1,
                               w2);
            source += ms->source(st.ms_v, mu_s_t, st.rayleigh_scattering + st.mie_scattering, w1, w2);
        }
        L += st.weight * source;
    }
    return L * batch.solar_irradiance();
}

// inscatter() with the transmittance and multiple-scattering LUTs for many views along one
// ray, prepared with the transmittance LUT `tlut`, that share the sun's zenith cosine mu_s and differ in
// nu: out[i] = inscatter(batch, &ms, ray, mu_s, nu[i], tlut.to_sun). A row of the
// sky-view LUT. Only the sun's zenith cosine at a step depends on nu, and linearly,
//   mu_s(t) = (r0 mu_s + t nu) / r(t) = A + B nu,  A = r0 mu_s / r(t),  B = t / r(t),
// and the phase functions factor out of the sum over steps:
//   L = E_sun [ P_R(nu) sum w sigma_R T_sun + P_M(nu) sum w sigma_M T_sun + sum w J_ms ],
// so each step is one pass over the views that computes every mu_s(t) and texel
// coordinate (arithmetic only: it vectorises) and one that fetches and accumulates. The
// weights of J_ms's three moments depend on the step alone (the view's zenith cosine
// there is the same for every nu), so they are combined into one row of texels per step
// (MultiScatteringLut::source_row) and each view does one linear lookup in it.
// `scratch` is reused between calls (no allocation once it is large enough).
struct InscatterRowScratch {
    std::vector<int> i_sun, i_ms;
    std::vector<float> fx_sun, fraction, fx_ms;
    std::vector<Float4> sum_rayleigh, sum_mie, sum_ms;
    std::vector<Spectrum4> ms_source;
};
void inscatter_row(const AtmosphereBatch& batch, const MultiScatteringLut& ms, const RaySamples& ray,
                   double mu_s, std::span<const float> nu, std::span<Spectrum4> out,
                   InscatterRowScratch& scratch);

}  // namespace welkin
