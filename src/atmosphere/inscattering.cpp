// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/inscattering.hpp"

#include <algorithm>

namespace welkin {
namespace {

// The arithmetic pass of one step: for every view, mu_s(t) = A + B nu, the transmittance
// lookup's texel and weights, and the multiple-scattering lookup's (ms.texel_x). The
// arrays do not overlap (__restrict), which lets the compiler vectorise the loop.
WELKIN_SIMD_CLONES_WIDE void coordinates(const TransmittanceLut::AtRadius& at_in, float A, float B,
                                         float ms_scale, int ms_last, const float* __restrict nu,
                                         std::size_t n, int* __restrict i_sun, float* __restrict fx_sun,
                                         float* __restrict fraction, int* __restrict i_ms,
                                         float* __restrict fx_ms) {
    const TransmittanceLut::AtRadius at = at_in;
    for (std::size_t i = 0; i < n; ++i) {
        const float mu_s_t = clamp_value(A + B * nu[i], -1.0f, 1.0f);
        float x;
        TransmittanceLut::sun_lookup(at, mu_s_t, x, fraction[i]);
        Texture2D::Row::split(x, at.row.last, i_sun[i], fx_sun[i]);
        Texture2D::Row::split((mu_s_t + 1.0f) * ms_scale, ms_last, i_ms[i], fx_ms[i]);
    }
}

}  // namespace

WELKIN_SIMD_CLONES_WIDE void inscatter_row(const AtmosphereBatch& batch, const MultiScatteringLut& ms,
                                           const RaySamples& ray, double mu_s, std::span<const float> nu,
                                           std::span<Spectrum4> out, InscatterRowScratch& scratch) {
    const std::size_t n = nu.size();
    if (ray.steps.empty()) {  // a ray that crosses no air
        std::fill(out.begin(), out.end(), Spectrum4(0.0f));
        return;
    }
    const Float4 zero = {0.0f, 0.0f, 0.0f, 0.0f};
    scratch.i_sun.resize(n);
    scratch.i_ms.resize(n);
    scratch.fx_sun.resize(n);
    scratch.fraction.resize(n);
    scratch.fx_ms.resize(n);
    scratch.sum_rayleigh.assign(n, zero);
    scratch.sum_mie.assign(n, zero);
    scratch.sum_ms.assign(n, zero);
    int* const i_sun = scratch.i_sun.data();
    int* const i_ms = scratch.i_ms.data();
    float* const fx_sun = scratch.fx_sun.data();
    float* const fraction = scratch.fraction.data();
    float* const fx_ms = scratch.fx_ms.data();
    Float4* const sum_r = scratch.sum_rayleigh.data();
    Float4* const sum_m = scratch.sum_mie.data();
    Float4* const sum_ms = scratch.sum_ms.data();
    const float* const nu_p = nu.data();
    const int ms_last = ms.texture().width() - 1;
    const float ms_scale = 0.5f * float(ms_last);
    for (const RaySamples::Step& st : ray.steps) {
        const float A = float(ray.r0 * mu_s / st.r), B = float(st.t / st.r);
        const TransmittanceLut::AtRadius& at = st.sun_at;  // from prepare_ray
        coordinates(at, A, B, ms_scale, ms_last, nu_p, n, i_sun, fx_sun, fraction, i_ms, fx_ms);
        const Spectrum4 w_r4 = st.weight * st.rayleigh_scattering, w_m4 = st.weight * st.mie_scattering;
        Spectrum4 w1, w2;
        ms.source_weights(st.rayleigh_scattering, st.mie_scattering, view_zenith_cosine(ray, st), w1, w2);
        // One texel row (lo == hi) of the combined source at this step's radius.
        const Spectrum4* const line =
            ms.source_row(st.r, w_r4 + w_m4, st.weight * w1, st.weight * w2, scratch.ms_source).lo;
        const Float4 w_r = to_float4(w_r4), w_m = to_float4(w_m4);
        for (std::size_t i = 0; i < n; ++i) {
            const Float4 T = at.row.sample4(i_sun[i], fx_sun[i]) * fraction[i];
            sum_r[i] += w_r * T;
            sum_m[i] += w_m * T;
            const Float4 j0 = to_float4(line[i_ms[i]]), j1 = to_float4(line[i_ms[i] + 1]);
            sum_ms[i] += j0 + fx_ms[i] * (j1 - j0);
        }
    }
    const Float4 E = to_float4(batch.solar_irradiance());
    for (std::size_t i = 0; i < n; ++i)
        out[i] = to_vec4(
            (sum_r[i] * batch.rayleigh_phase(nu_p[i]) + sum_m[i] * batch.mie_phase(nu_p[i]) + sum_ms[i]) * E);
}

}  // namespace welkin
