// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/multiscattering_lut.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/inscattering.hpp"
#include "welkin/atmosphere/phase.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/quadrature.hpp"

namespace welkin {
namespace {

// The arithmetic pass over the (phi, mu_s) pairs at one point: mu_s there = C mu_s + D
// sin_s cos(phi), clamped, and the transmittance lookup's texel and weights, the visible
// fraction weighed by clamp(mu_s, cosine_floor, 1): by 1 for the sun seen from the air
// (floor 1), by the cosine of the sun on the ground, max(mu_s, 0), for the ground (floor
// 0). (A flag and a select there kept GCC from vectorising the loop.) The arrays do not
// overlap (__restrict), which lets the compiler vectorise it.
WELKIN_SIMD_CLONES_WIDE void sun_coordinates(const TransmittanceLut::AtRadius& at_in, float C, float D,
                                             const float* __restrict mu_s, const float* __restrict sin_cos,
                                             std::size_t n, float cosine_floor, int* __restrict texel,
                                             float* __restrict fx, float* __restrict fraction) {
    const TransmittanceLut::AtRadius at = at_in;
    for (std::size_t l = 0; l < n; ++l) {
        const float mu = clamp_value(C * mu_s[l] + D * sin_cos[l], -1.0f, 1.0f);
        float x, f;
        TransmittanceLut::sun_lookup(at, mu, x, f);
        Texture2D::Row::split(x, at.row.last, texel[l], fx[l]);
        fraction[l] = f * clamp_value(mu, cosine_floor, 1.0f);
    }
}

}  // namespace

namespace {

// The (phi, mu_s) pairs of a row, l = b size + i: mu_s of texel column i and
// sin_s cos(phi) for azimuth stratum b of n_phi over [0, pi].
struct SunPairs {
    std::vector<float> mu_s, sin_cos;

    SunPairs(int n_phi, int size) : mu_s(std::size_t(n_phi) * size), sin_cos(mu_s.size()) {
        for (int b = 0; b < n_phi; ++b) {
            const double cos_phi = std::cos(kPi * (double(b) + 0.5) / double(n_phi));
            for (int i = 0; i < size; ++i) {
                const double mu =
                    clamp_cosine(2.0 * unit_from_texcoord((float(i) + 0.5f) / float(size), size) - 1.0);
                mu_s[std::size_t(b) * size + i] = float(mu);
                sin_cos[std::size_t(b) * size + i] = float(safe_sqrt(1.0 - mu * mu) * cos_phi);
            }
        }
    }
};

}  // namespace

// Row j of the three textures from the moments of the arriving light's first order summed
// over the directions (m0, m1, m2 per pair) and the transfer's (f0, f1, f2): orders >= 2
// are a geometric series in <f'> for the mean, Psi_ms f'(w) for its shape.
void MultiScatteringLut::store_row(int j, int n_phi, const std::vector<Spectrum4>& m0,
                                   const std::vector<Spectrum4>& m1, const std::vector<Spectrum4>& m2,
                                   const std::vector<Spectrum4>& m_up, const Spectrum4& f0,
                                   const Spectrum4& f1, const Spectrum4& f2, const Spectrum4& f_up) {
    const int size = texture_.width();
    const Spectrum4 series = 1.0f / glm::max(Spectrum4(1.0f) - f0, Spectrum4(1e-3f));
    for (int i = 0; i < size; ++i) {
        Spectrum4 s0(0.0f), s1(0.0f), s2(0.0f), s_up(0.0f);
        for (int b = 0; b < n_phi; ++b) {
            const std::size_t l = std::size_t(b) * size + i;
            s0 += m0[l];
            s1 += m1[l];
            s2 += m2[l];
            s_up += m_up[l];
        }
        const Spectrum4 psi = s0 * series;
        texture_.at(i, j) = psi;
        dipole_.at(i, j) = 3.0f * (s1 + psi * f1);
        quadrupole_.at(i, j) = 5.0f * (s2 + psi * f2);
        // The upper hemisphere's mean; never above twice the sphere's (rounding).
        upper_.at(i, j) = glm::min(2.0f * (s_up + psi * f_up), 2.0f * psi);
    }
}

// Texel (i, j) holds the moments a_0 = Psi_ms, a_1, a_2 for mu_s = -1 + 2 x_i and r = R + (top - R) x_j (x on
// the texel-centre grid of texcoord_from_unit). One row shares its radius, so each of the row's rays (a
// direction w about the local zenith) is marched once and reused for all 32 sun angles: only the sun's
// transmittance along it and the phase functions depend on mu_s. The transfer f' of a ray does not depend on
// the sun at all. See the header for the derivation.
//
// For the ray w = (sin(theta) cos(phi), sin(theta) sin(phi), mu) and the sun at
// (sin_s, 0, mu_s), nu = mu mu_s + sin(theta) cos(phi) sin_s, and the sun's zenith cosine
// at distance t along w is (Bruneton 2017, mu_s_d)
//   mu_s(t) = (r mu_s + t nu) / r(t) = mu_s (r + t mu) / r(t) + sin_s cos(phi) t sin(theta) / r(t),
// two per-step constants times two per-(phi, sun angle) ones. So each step of a ray is one
// pass over all (phi, mu_s) pairs that computes the lookups' texel coordinates
// (arithmetic only: it vectorises) and one that fetches and accumulates, per constituent
// (the phase functions, which depend on nu = mu mu_s + sin(theta) sin_s cos(phi), multiply
// each ray's two sums once it is done).
MultiScatteringLut::MultiScatteringLut(const AtmosphereBatch& batch, const TransmittanceLut& tlut, int size,
                                       int directions_sqrt, int steps)
    : bottom_(batch.bottom_radius()),
      top_(batch.top_radius()),
      mie_chi1_(mie_phase_moment(batch.mie_phase_model(), 1, batch.mie_g())),
      mie_chi2_(mie_phase_moment(batch.mie_phase_model(), 2, batch.mie_g())),
      texture_(size, size),
      dipole_(size, size),
      quadrupole_(size, size),
      upper_(size, size) {
    if (directions_sqrt < 2 || directions_sqrt % 2 != 0)
        throw InvalidArgument("directions_sqrt", "must be an even number >= 2");
    const double R = bottom_, top = top_;
    const Spectrum4 albedo = batch.ground_albedo();
    const Spectrum4 albedo_over_pi = albedo * float(1.0 / kPi);
    // Cosines: Gauss-Legendre on each hemisphere (the light is sharp at the horizon).
    // Azimuths: strata over [0, pi]; the sky around the point is symmetric about the sun's
    // vertical plane, so half the strata give the same sum as [0, 2 pi) at half the cost.
    const int n_half = directions_sqrt / 2, n_phi = std::max(1, directions_sqrt / 2);
    std::vector<double> gl_x, gl_w;
    gauss_legendre_unit(n_half, gl_x, gl_w);
    const TransmittanceLut::AtRadius ground_at = tlut.at_radius(R);
    const SunPairs pairs(n_phi, size);
    const std::size_t n_pairs = pairs.mu_s.size();
    const float* const pm = pairs.mu_s.data();
    const float* const psc = pairs.sin_cos.data();
    tbb::parallel_for(tbb::blocked_range<int>(0, size), [&](const tbb::blocked_range<int>& rows) {
        RaySamples ray;
        std::vector<int> texel_buf(n_pairs);
        std::vector<float> fx_buf(n_pairs), fraction_buf(n_pairs);
        // Per pair, this ray's sums of w sigma_R T_sun and w sigma_M T_sun, then the light
        // L' it brings (phases applied, ground added).
        std::vector<Float4> sum_r_buf(n_pairs), sum_m_buf(n_pairs), ground_buf(n_pairs);
        // Per pair, <L'>, <L' P_1>, <L' P_2> and <L' 1_up> summed over the directions.
        std::vector<Spectrum4> m0_buf(n_pairs), m1_buf(n_pairs), m2_buf(n_pairs), up_buf(n_pairs);
        int* const texel = texel_buf.data();
        float* const fx = fx_buf.data();
        float* const fraction = fraction_buf.data();
        Float4* const sum_r = sum_r_buf.data();
        Float4* const sum_m = sum_m_buf.data();
        Float4* const ground = ground_buf.data();
        const Float4 zero = {0.0f, 0.0f, 0.0f, 0.0f};
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const double r =
                R + (top - R) * clamp01(double(unit_from_texcoord((float(j) + 0.5f) / float(size), size)));
            for (auto* m : {&m0_buf, &m1_buf, &m2_buf, &up_buf})
                std::fill(m->begin(), m->end(), Spectrum4(0.0f));
            Spectrum4 f0(0.0f), f1(0.0f), f2(0.0f), f_up(0.0f);  // <f'>, <f' P_1>, <f' P_2>, <f' 1_up>
            for (int a = 0; a < 2 * n_half; ++a) {
                const double mu = a < n_half ? gl_x[std::size_t(a)] : -gl_x[std::size_t(a - n_half)];
                // This cosine's weight in the mean over the sphere (each hemisphere's sum to 1),
                // shared by the n_phi azimuths.
                const float w_mu = float(0.5 * gl_w[std::size_t(a % n_half)]), w_dir = w_mu / float(n_phi);
                const float p1 = float(mu), p2 = float(0.5 * (3.0 * mu * mu - 1.0));
                const double sin_theta = safe_sqrt(1.0 - mu * mu);
                prepare_ray(batch, r, mu, steps, ray, &tlut);
                std::fill(sum_r_buf.begin(), sum_r_buf.end(), zero);
                std::fill(sum_m_buf.begin(), sum_m_buf.end(), zero);
                std::fill(ground_buf.begin(), ground_buf.end(), zero);
                Spectrum4 f(0.0f);
                for (const RaySamples::Step& st : ray.steps) {
                    const Spectrum4 w_r = st.weight * st.rayleigh_scattering,
                                    w_m = st.weight * st.mie_scattering;
                    f += w_r + w_m;
                    const float C = float((r + st.t * mu) / st.r), D = float(st.t * sin_theta / st.r);
                    const TransmittanceLut::AtRadius& at = st.sun_at;
                    sun_coordinates(at, C, D, pm, psc, n_pairs, 1.0f, texel, fx, fraction);
                    const Float4 w_r4 = to_float4(w_r), w_m4 = to_float4(w_m);
                    for (std::size_t l = 0; l < n_pairs; ++l) {
                        // The sun below this point's horizon adds nothing: skip the fetch
                        // (whole runs of pairs, so the branch is well predicted).
                        if (fraction[l] == 0.0f) continue;
                        const Float4 T = at.row.sample4(texel[l], fx[l]) * fraction[l];
                        sum_r[l] += w_r4 * T;
                        sum_m[l] += w_m4 * T;
                    }
                }
                const bool hits_ground = ray_hits_ground(r, mu, R);
                // The ground lit by the isotropic field of each order (irradiance pi m_n)
                // adds albedo m_n T_g to the next order along this ray: f' = f + albedo T_g.
                if (hits_ground) f += ray.transmittance * albedo;
                f0 += f * w_mu;
                f1 += f * (w_mu * p1);
                f2 += f * (w_mu * p2);
                const float in_up = a < n_half ? 1.0f : 0.0f;  // the indicator 1_up
                f_up += f * (w_mu * in_up);
                if (hits_ground) {
                    // Sun light reflected by the Lambertian ground at the ray's end, where
                    // mu_s = (r mu_s + d nu) / R.
                    const double d = distance_to_bottom(r, mu, R);
                    const float C = float((r + d * mu) / R), D = float(d * sin_theta / R);
                    const Float4 k = to_float4(ray.transmittance * albedo_over_pi);
                    sun_coordinates(ground_at, C, D, pm, psc, n_pairs, 0.0f, texel, fx, fraction);
                    for (std::size_t l = 0; l < n_pairs; ++l)
                        ground[l] = (k * fraction[l]) * ground_at.row.sample4(texel[l], fx[l]);
                }
                // L' = the single-scattered light with the real phase functions at
                // nu = w . s (light from w travels along -w, the sun's along -s), plus the
                // ground; accumulated into the three moments.
                for (std::size_t l = 0; l < n_pairs; ++l) {
                    const float nu = clamp_value(float(mu) * pm[l] + float(sin_theta) * psc[l], -1.0f, 1.0f);
                    const Spectrum4 L = to_vec4(
                        (sum_r[l] * batch.rayleigh_phase(nu) + sum_m[l] * batch.mie_phase(nu) + ground[l]) *
                        w_dir);
                    m0_buf[l] += L;
                    m1_buf[l] += L * p1;
                    m2_buf[l] += L * p2;
                    up_buf[l] += L * in_up;
                }
            }
            store_row(j, n_phi, m0_buf, m1_buf, m2_buf, up_buf, f0, f1, f2, f_up);
        }
    });
}

}  // namespace welkin
