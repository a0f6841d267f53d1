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
    tbb::parallel_for(0, size, [&](int j) {
        const double r = R + (top - R) * clamp01(double(unit_from_texcoord((float(j) + 0.5f) / float(size), size)));
        std::vector<Spectrum4> L2(std::size_t(size), Spectrum4(0.0f));
        Spectrum4 f_ms(0.0f);
        RaySamples ray;
        for (int a = 0; a < directions_sqrt; ++a) {
            // Stratified uniform directions: cos(theta) uniform in [-1, 1], phi in [0, pi].
            const double mu = 1.0 - 2.0 * (double(a) + 0.5) / double(directions_sqrt);
            const double sin_theta = safe_sqrt(1.0 - mu * mu);
            prepare_ray(batch, r, mu, steps, ray, &tlut);
            const bool hits_ground = ray_hits_ground(r, mu, R);
            const double d = distance_to_boundary(r, mu, R, top);
            Spectrum4 f(0.0f);
            for (const RaySamples::Step& st : ray.steps) f += st.weight * (st.rayleigh_scattering + st.mie_scattering);
            f_ms += f * float(n_phi);
            for (int b = 0; b < n_phi; ++b) {
                const double cos_phi = std::cos(kPi * (double(b) + 0.5) / double(n_phi));
                for (int i = 0; i < size; ++i) {
                    const double mu_s = clamp_cosine(2.0 * unit_from_texcoord((float(i) + 0.5f) / float(size), size) - 1.0);
                    const double nu = sin_theta * cos_phi * safe_sqrt(1.0 - mu_s * mu_s) + mu * mu_s;
                    Spectrum4 L(0.0f);
                    for (const RaySamples::Step& st : ray.steps) {
                        const double mu_s_t = clamp_cosine((r * mu_s + st.t * nu) / st.r);
                        L += st.weight * (st.rayleigh_scattering + st.mie_scattering) * tlut.to_sun(st.sun_at, mu_s_t);
                    }
                    L *= p_u;
                    if (hits_ground) {
                        // Sun light reflected by the Lambertian ground at the ray's end.
                        const double mu_s_g = clamp_cosine((r * mu_s + d * nu) / R);
                        L += ray.transmittance * tlut.to_sun(ground_at, mu_s_g) *
                             float(std::max(mu_s_g, 0.0)) * albedo_over_pi;
                    }
                    L2[std::size_t(i)] += L;
                }
            }
        }
        f_ms *= inv_dirs;
        // Each order >= 2 carries f_ms of the one before: a geometric series.
        for (int i = 0; i < size; ++i)
            texture_.at(i, j) = L2[std::size_t(i)] * inv_dirs / glm::max(Spectrum4(1.0f) - f_ms, Spectrum4(1e-3f));
    });
}

}  // namespace welkin
