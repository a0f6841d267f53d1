#include "welkin/multiscattering_lut.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "welkin/geometry.hpp"
#include "welkin/inscattering.hpp"
#include "welkin/phase.hpp"

namespace welkin {

// Texel (i, j) holds Psi_ms for mu_s = -1 + 2 x_i and r = R + (top - R) x_j (x on the
// texel-centre grid of texcoord_from_unit). One row shares its radius, so each of the
// row's rays (a direction w about the local zenith) is marched once and reused for all 32
// sun angles: only the sun's transmittance along it depends on mu_s. The transfer f of a
// ray does not depend on the sun at all.
//
// For the ray w = (sin(theta) cos(phi), sin(theta) sin(phi), mu) and the sun at
// (sin_s, 0, mu_s), nu = mu mu_s + sin(theta) cos(phi) sin_s, and the sun's zenith cosine
// at distance t along w is (Bruneton 2017, mu_s_d)
//   mu_s(t) = (r mu_s + t nu) / r(t) = mu_s (r + t mu) / r(t) + sin_s cos(phi) t sin(theta) / r(t),
// two per-step constants times two per-(phi, sun angle) ones. So each step of a ray is one
// pass over all (phi, mu_s) pairs that computes the lookups' texel coordinates
// (arithmetic only: it vectorises) and one that fetches and accumulates.
MultiScatteringLut::MultiScatteringLut(const AtmosphereBatch& batch, const TransmittanceLut& tlut,
                                       int size, int directions_sqrt, int steps)
    : bottom_(batch.bottom_radius()), top_(batch.top_radius()), texture_(size, size) {
    const double R = bottom_, top = top_;
    const float p_u = float(kIsotropicPhase);
    const Spectrum4 albedo_over_pi = batch.ground_albedo() * float(1.0 / kPi);
    // The sky around the point is symmetric about the sun's vertical plane, so azimuths in
    // [0, pi] with half the strata give the same sum as [0, 2 pi) at half the cost.
    const int n_phi = std::max(1, directions_sqrt / 2);
    const float inv_dirs = 1.0f / float(directions_sqrt * n_phi);
    const TransmittanceLut::AtRadius ground_at = tlut.at_radius(R);
    // The (phi, mu_s) pairs, l = b size + i: mu_s and sin_s cos(phi).
    const std::size_t n_pairs = std::size_t(n_phi) * std::size_t(size);
    std::vector<float> pair_mu_s(n_pairs), pair_sin_cos(n_pairs);
    for (int b = 0; b < n_phi; ++b) {
        const double cos_phi = std::cos(kPi * (double(b) + 0.5) / double(n_phi));
        for (int i = 0; i < size; ++i) {
            const double mu_s = clamp_cosine(2.0 * unit_from_texcoord((float(i) + 0.5f) / float(size), size) - 1.0);
            pair_mu_s[std::size_t(b) * size + i] = float(mu_s);
            pair_sin_cos[std::size_t(b) * size + i] = float(safe_sqrt(1.0 - mu_s * mu_s) * cos_phi);
        }
    }
    const float* const pm = pair_mu_s.data();
    const float* const psc = pair_sin_cos.data();
    tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
        RaySamples ray;
        std::vector<float> x_buf(n_pairs), fraction_buf(n_pairs);
        std::vector<Spectrum4> L2_buf(n_pairs);
        float* const x = x_buf.data();
        float* const fraction = fraction_buf.data();
        Spectrum4* const L2 = L2_buf.data();  // per pair, summed over the directions
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const double r = R + (top - R) * clamp01(double(unit_from_texcoord((float(j) + 0.5f) / float(size), size)));
            std::fill(L2_buf.begin(), L2_buf.end(), Spectrum4(0.0f));
            Spectrum4 f_ms(0.0f);
            for (int a = 0; a < directions_sqrt; ++a) {
                // Stratified uniform directions: cos(theta) uniform in [-1, 1], phi in [0, pi].
                const double mu = 1.0 - 2.0 * (double(a) + 0.5) / double(directions_sqrt);
                const double sin_theta = safe_sqrt(1.0 - mu * mu);
                prepare_ray(batch, r, mu, steps, ray, &tlut);
                Spectrum4 f(0.0f);
                for (const RaySamples::Step& st : ray.steps) {
                    const Spectrum4 w = st.weight * (st.rayleigh_scattering + st.mie_scattering) * p_u;
                    f += st.weight * (st.rayleigh_scattering + st.mie_scattering);
                    const float C = float((r + st.t * mu) / st.r), D = float(st.t * sin_theta / st.r);
                    const TransmittanceLut::AtRadius& at = st.sun_at;
                    for (std::size_t l = 0; l < n_pairs; ++l)
                        TransmittanceLut::sun_lookup(at, clamp_value(C * pm[l] + D * psc[l], -1.0f, 1.0f), x[l], fraction[l]);
                    for (std::size_t l = 0; l < n_pairs; ++l) L2[l] += w * (at.row.sample(x[l]) * fraction[l]);
                }
                f_ms += f * float(n_phi);
                if (ray_hits_ground(r, mu, R)) {
                    // Sun light reflected by the Lambertian ground at the ray's end, where
                    // mu_s = (r mu_s + d nu) / R.
                    const double d = distance_to_bottom(r, mu, R);
                    const float C = float((r + d * mu) / R), D = float(d * sin_theta / R);
                    const Spectrum4 k = ray.transmittance * albedo_over_pi;
                    for (std::size_t l = 0; l < n_pairs; ++l) {
                        const float mu_s_g = clamp_value(C * pm[l] + D * psc[l], -1.0f, 1.0f);
                        TransmittanceLut::sun_lookup(ground_at, mu_s_g, x[l], fraction[l]);
                        fraction[l] *= max_value(mu_s_g, 0.0f);
                    }
                    for (std::size_t l = 0; l < n_pairs; ++l) L2[l] += k * (ground_at.row.sample(x[l]) * fraction[l]);
                }
            }
            f_ms *= inv_dirs;
            // Each order >= 2 carries f_ms of the one before: a geometric series.
            const Spectrum4 series = inv_dirs / glm::max(Spectrum4(1.0f) - f_ms, Spectrum4(1e-3f));
            for (int i = 0; i < size; ++i) {
                Spectrum4 sum(0.0f);
                for (int b = 0; b < n_phi; ++b) sum += L2[std::size_t(b) * size + i];
                texture_.at(i, j) = sum * series;
            }
        }
    });
}

}  // namespace welkin
