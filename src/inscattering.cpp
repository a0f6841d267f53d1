#include "welkin/inscattering.hpp"

namespace welkin {

void inscatter_row(const AtmosphereBatch& batch, const MultiScatteringLut& ms,
                   const RaySamples& ray, double mu_s, std::span<const float> nu, std::span<Spectrum4> out,
                   InscatterRowScratch& scratch) {
    const std::size_t n = nu.size();
    scratch.x_sun.resize(n);
    scratch.fraction.resize(n);
    scratch.x_ms.resize(n);
    scratch.sum_rayleigh.assign(n, Spectrum4(0.0f));
    scratch.sum_mie.assign(n, Spectrum4(0.0f));
    scratch.sum_ms.assign(n, Spectrum4(0.0f));
    float* const x_sun = scratch.x_sun.data();
    float* const fraction = scratch.fraction.data();
    float* const x_ms = scratch.x_ms.data();
    Spectrum4* const sum_r = scratch.sum_rayleigh.data();
    Spectrum4* const sum_m = scratch.sum_mie.data();
    Spectrum4* const sum_ms = scratch.sum_ms.data();
    const float* const nu_p = nu.data();
    for (const RaySamples::Step& st : ray.steps) {
        const float A = float(ray.r0 * mu_s / st.r), B = float(st.t / st.r);
        const TransmittanceLut::AtRadius& at = st.sun_at;  // from prepare_ray
        for (std::size_t i = 0; i < n; ++i) {
            const float mu_s_t = clamp_value(A + B * nu_p[i], -1.0f, 1.0f);
            TransmittanceLut::sun_lookup(at, mu_s_t, x_sun[i], fraction[i]);
            x_ms[i] = ms.texel_x(mu_s_t);
        }
        const Spectrum4 w_r = st.weight * st.rayleigh_scattering, w_m = st.weight * st.mie_scattering;
        Spectrum4 w1, w2;
        ms.source_weights(st.rayleigh_scattering, st.mie_scattering, view_zenith_cosine(ray, st), w1, w2);
        const Texture2D::Row ms_row =
            ms.source_row(st.r, w_r + w_m, st.weight * w1, st.weight * w2, scratch.ms_source);
        for (std::size_t i = 0; i < n; ++i) {
            const Spectrum4 T = at.row.sample(x_sun[i]) * fraction[i];
            sum_r[i] += w_r * T;
            sum_m[i] += w_m * T;
            sum_ms[i] += ms_row.sample(x_ms[i]);
        }
    }
    const Spectrum4 E = batch.solar_irradiance();
    for (std::size_t i = 0; i < n; ++i)
        out[i] = (sum_r[i] * batch.rayleigh_phase(nu_p[i]) + sum_m[i] * batch.mie_phase(nu_p[i]) + sum_ms[i]) * E;
}

}  // namespace welkin
