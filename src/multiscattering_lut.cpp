#include "welkin/multiscattering_lut.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "welkin/geometry.hpp"
#include "welkin/phase.hpp"

namespace welkin {

MultiScatteringLut::MultiScatteringLut(const AtmosphereBatch& batch, const TransmittanceLut& tlut,
                                       int size, int directions_sqrt, int steps)
    : bottom_(batch.bottom_radius()), top_(batch.top_radius()), texture_(size, size) {
    const double R = bottom_, top = top_;
    const float p_u = float(kIsotropicPhase);
    const Spectrum4 albedo_over_pi = batch.ground_albedo() * float(1.0 / kPi);
    // The sky around the point is symmetric about the sun's vertical plane, so azimuths in
    // [0, pi] with half the strata give the same sum as [0, 2 pi) at half the cost.
    const int n_phi = std::max(1, directions_sqrt / 2);
    const int n_dirs = directions_sqrt * n_phi;
    tbb::parallel_for(0, size * size, [&](int texel) {
        const int i = texel % size, j = texel / size;
        const double mu_s = clamp_cosine(2.0 * unit_from_texcoord((float(i) + 0.5f) / float(size), size) - 1.0);
        const double r = R + (top - R) * clamp01(double(unit_from_texcoord((float(j) + 0.5f) / float(size), size)));
        const double sun_sin = safe_sqrt(1.0 - mu_s * mu_s);
        Spectrum4 L2(0.0f), f_ms(0.0f);
        for (int a = 0; a < directions_sqrt; ++a) {
            for (int b = 0; b < n_phi; ++b) {
                // Stratified uniform directions: cos(theta) uniform in [-1, 1], phi in [0, 2 pi).
                const double mu = 1.0 - 2.0 * (double(a) + 0.5) / double(directions_sqrt);
                const double phi = kPi * (double(b) + 0.5) / double(n_phi);
                const double nu = safe_sqrt(1.0 - mu * mu) * std::cos(phi) * sun_sin + mu * mu_s;
                const bool hits_ground = ray_hits_ground(r, mu, R);
                const double d = distance_to_boundary(r, mu, R, top);
                Spectrum4 T(1.0f), L(0.0f), f(0.0f);
                for (int k = 0; k < steps; ++k) {
                    const double s0 = double(k) / steps, s1 = double(k + 1) / steps, sm = (k + 0.5) / steps;
                    const double dt = d * (s1 * s1 - s0 * s0), t = d * sm * sm;
                    const double r_t = radius_at(r, mu, t);
                    const double mu_s_t = clamp_cosine((r * mu_s + t * nu) / r_t);
                    const MediumSample m = batch.sample(r_t - R);
                    const Spectrum4 sigma_s = m.rayleigh_scattering + m.mie_scattering;
                    const Spectrum4 T_seg = glm::exp(-m.extinction * float(dt));
                    Spectrum4 integral;
                    for (int c = 0; c < 4; ++c)
                        integral[c] = m.extinction[c] > 1e-12f ? (1.0f - T_seg[c]) / m.extinction[c] : float(dt);
                    L += T * sigma_s * tlut.to_sun(r_t, mu_s_t) * p_u * integral;
                    f += T * sigma_s * integral;
                    T *= T_seg;
                }
                if (hits_ground) {
                    // Sun light reflected by the Lambertian ground at the ray's end.
                    const double r_g = R;
                    const double mu_s_g = clamp_cosine((r * mu_s + d * nu) / r_g);
                    L += T * tlut.to_sun(r_g, mu_s_g) * float(std::max(mu_s_g, 0.0)) * albedo_over_pi;
                }
                L2 += L;
                f_ms += f;
            }
        }
        L2 /= float(n_dirs);
        f_ms /= float(n_dirs);
        // Each order >= 2 carries f_ms of the one before: a geometric series.
        texture_.at(i, j) = L2 / glm::max(Spectrum4(1.0f) - f_ms, Spectrum4(1e-3f));
    });
}

}  // namespace welkin
