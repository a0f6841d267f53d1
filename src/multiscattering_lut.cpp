#include "welkin/multiscattering_lut.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "welkin/error.hpp"
#include "welkin/geometry.hpp"
#include "welkin/inscattering.hpp"
#include "welkin/phase.hpp"

namespace welkin {
namespace {

// n-point Gauss-Legendre on (0, 1): nodes by Newton's method on P_n from Tricomi's
// initial guesses, weights 2 / ((1 - x^2) P_n'(x)^2) halved for the unit interval.
void gauss_legendre_unit(int n, std::vector<double>& x, std::vector<double>& w) {
    x.resize(std::size_t(n));
    w.resize(std::size_t(n));
    for (int i = 0; i < n; ++i) {
        double t = std::cos(kPi * (double(i) + 0.75) / (double(n) + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            const double dt = p1 / dp;
            t -= dt;
            if (std::abs(dt) < 1e-15) break;
        }
        x[std::size_t(i)] = 0.5 * (1.0 + t);
        w[std::size_t(i)] = 1.0 / ((1.0 - t * t) * dp * dp);
    }
}

}  // namespace

// Texel (i, j) holds the moments for mu_s = -1 + 2 x_i and r = R + (top - R) x_j (x on the
// texel-centre grid of texcoord_from_unit). One row shares its radius, so each of the
// row's rays (a direction w about the local zenith) is marched once and reused for all 32
// sun angles: only the sun's transmittance along it and the phase functions depend on
// mu_s. The transfer f' of a ray does not depend on the sun at all. See the header for
// the derivation.
MultiScatteringLut::MultiScatteringLut(const AtmosphereBatch& batch, const TransmittanceLut& tlut,
                                       int size, int directions_sqrt, int steps)
    : bottom_(batch.bottom_radius()),
      top_(batch.top_radius()),
      mie_chi1_(mie_phase_moment(batch.mie_phase_model(), 1, batch.mie_g())),
      mie_chi2_(mie_phase_moment(batch.mie_phase_model(), 2, batch.mie_g())),
      texture_(size, size),
      dipole_(size, size),
      quadrupole_(size, size) {
    if (directions_sqrt < 2 || directions_sqrt % 2 != 0)
        throw InvalidArgument("directions_sqrt", "must be an even number >= 2");
    const double R = bottom_, top = top_;
    const Spectrum4 albedo = batch.ground_albedo();
    const Spectrum4 albedo_over_pi = albedo * float(1.0 / kPi);
    // Cosines: Gauss-Legendre on each hemisphere; azimuths: midpoints of strata over
    // [0, pi], the sky around the point being symmetric about the sun's vertical plane.
    const int n_half = directions_sqrt / 2, n_phi = std::max(1, directions_sqrt / 2);
    std::vector<double> gl_x, gl_w;
    gauss_legendre_unit(n_half, gl_x, gl_w);
    std::vector<double> cos_phi(static_cast<std::size_t>(n_phi));
    for (int b = 0; b < n_phi; ++b) cos_phi[std::size_t(b)] = std::cos(kPi * (double(b) + 0.5) / double(n_phi));
    const TransmittanceLut::AtRadius ground_at = tlut.at_radius(R);
    tbb::parallel_for(0, size, [&](int j) {
        const double r = R + (top - R) * clamp01(double(unit_from_texcoord((float(j) + 0.5f) / float(size), size)));
        // <L' P_l> per sun angle, and <f' P_l>; <.> the mean over the sphere.
        std::vector<Spectrum4> m0(std::size_t(size), Spectrum4(0.0f)), m1 = m0, m2 = m0;
        Spectrum4 f0(0.0f), f1(0.0f), f2(0.0f);
        RaySamples ray;
        for (int a = 0; a < 2 * n_half; ++a) {
            const double mu = a < n_half ? gl_x[std::size_t(a)] : -gl_x[std::size_t(a - n_half)];
            // Weight of this cosine in the mean over the sphere (each hemisphere's weights sum to 1).
            const float w_mu = float(0.5 * gl_w[std::size_t(a % n_half)]);
            const float p1 = float(mu), p2 = float(0.5 * (3.0 * mu * mu - 1.0));
            const double sin_theta = safe_sqrt(1.0 - mu * mu);
            prepare_ray(batch, r, mu, steps, ray, &tlut);
            const bool hits_ground = ray_hits_ground(r, mu, R);
            const double d = distance_to_boundary(r, mu, R, top);
            Spectrum4 f(0.0f);
            for (const RaySamples::Step& st : ray.steps) f += st.weight * (st.rayleigh_scattering + st.mie_scattering);
            if (hits_ground) f += ray.transmittance * albedo;
            f0 += f * w_mu;
            f1 += f * (w_mu * p1);
            f2 += f * (w_mu * p2);
            const float w_dir = w_mu / float(n_phi);
            for (int b = 0; b < n_phi; ++b) {
                const double sin_cos = sin_theta * cos_phi[std::size_t(b)];
                for (int i = 0; i < size; ++i) {
                    const double mu_s = clamp_cosine(2.0 * unit_from_texcoord((float(i) + 0.5f) / float(size), size) - 1.0);
                    const double nu = sin_cos * safe_sqrt(1.0 - mu_s * mu_s) + mu * mu_s;
                    Spectrum4 sum_rayleigh(0.0f), sum_mie(0.0f);
                    for (const RaySamples::Step& st : ray.steps) {
                        const double mu_s_t = clamp_cosine((r * mu_s + st.t * nu) / st.r);
                        const Spectrum4 lit = st.weight * tlut.to_sun(st.sun_at, mu_s_t);
                        sum_rayleigh += lit * st.rayleigh_scattering;
                        sum_mie += lit * st.mie_scattering;
                    }
                    // Light arriving from w travels along -w; the sun's along -s: the
                    // scattering cosine is w . s = nu (phase.hpp).
                    Spectrum4 L = sum_rayleigh * batch.rayleigh_phase(float(nu)) + sum_mie * batch.mie_phase(float(nu));
                    if (hits_ground) {
                        // Sun light reflected by the Lambertian ground at the ray's end.
                        const double mu_s_g = clamp_cosine((r * mu_s + d * nu) / R);
                        L += ray.transmittance * tlut.to_sun(ground_at, mu_s_g) *
                             float(std::max(mu_s_g, 0.0)) * albedo_over_pi;
                    }
                    L *= w_dir;
                    m0[std::size_t(i)] += L;
                    m1[std::size_t(i)] += L * p1;
                    m2[std::size_t(i)] += L * p2;
                }
            }
        }
        // Orders >= 2 of the arriving light: a geometric series in <f'> for the mean,
        // and Psi_ms f'(w) for its shape.
        const Spectrum4 series = 1.0f / glm::max(Spectrum4(1.0f) - f0, Spectrum4(1e-3f));
        for (int i = 0; i < size; ++i) {
            const Spectrum4 psi = m0[std::size_t(i)] * series;
            texture_.at(i, j) = psi;
            dipole_.at(i, j) = 3.0f * (m1[std::size_t(i)] + psi * f1);
            quadrupole_.at(i, j) = 5.0f * (m2[std::size_t(i)] + psi * f2);
        }
    });
}

}  // namespace welkin
