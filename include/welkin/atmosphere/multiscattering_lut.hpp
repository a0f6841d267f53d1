// SPDX-License-Identifier: Apache-2.0
// Multiple-scattering LUT (Hillaire 2020, "A Scalable and Production Ready Sky and
// Atmosphere Rendering Technique", sec. 5.5, 32 x 32 texels), extended with the angular
// shape of the multiply-scattered light.
//
// Hillaire's model. For a point x at radius r lit by the sun at zenith cosine mu_s, all
// scattering orders >= 2 are approximated by assuming that the light reaching x after one
// or more bounces comes equally from every direction, and that each order carries a
// constant fraction f_ms of the previous one. With unit sun illuminance and the isotropic
// phase p_u = 1 / (4 pi):
//   L_2nd = integral over the sphere of L'(x, w) p_u dw, where L' is the single-scattered
//           radiance arriving from w plus the sun light the ground reflects (Lambertian),
//   f_ms  = integral over the sphere of (integral along w of T sigma_s dt) p_u dw,
//   Psi_ms = L_2nd (1 + f_ms + f_ms^2 + ...) = L_2nd / (1 - f_ms)          (eq. 9)
// and the point scatters sigma_s(x) Psi_ms(r, mu_s) E_sun towards any viewer (eq. 10).
//
// What that misses (measured against the reference path tracer, order by order, in
// tests/cpp/test_multiscattering_vs_reference.cpp; figures in docs/validation.md,
// "Multiple-scattering LUT"): Hillaire's term is too low near the horizon with the sun low
// and too high at the zenith with the sun overhead.
// The multiply-scattered light is not isotropic: seen from the low air it is brightest
// near the horizon (long paths), and Rayleigh's phase 3/4 (1 + nu^2) sends that light
// into a horizontal view with weight 3/4 (1 + cos^2) ~ 1.125 on average over the horizon
// but into a vertical view with 3/4. Its azimuthal structure about the sun is weaker: at
// fixed view zenith the reference's multiple scattering varies with the view azimuth by
// at most 8 % at 440 nm and 20 % at 680 nm (sun 60 deg, views near the horizon, where
// Mie scatters the bright horizon forwards).
//
// The extension: keep the light's dependence on the zenith angle. Write the radiance
// field of multiply-scattered light arriving at x from direction w, averaged over
// azimuth, as a Legendre series in mu_w = w . z (z the local zenith),
//   L_ms(x, w) = a_0 + a_1 P_1(mu_w) + a_2 P_2(mu_w) + ...,  a_0 = Psi_ms,
// and let it scatter towards a viewer looking along v: by the Funk-Hecke theorem
// (phase.hpp) each degree l comes out with the phase function's Legendre moment chi_l,
//   J_ms(x, v) = sum_k sigma_k(x) [a_0 + chi_k1 a_1 P_1(mu_v) + chi_k2 a_2 P_2(mu_v)],   (*)
// mu_v the view's zenith cosine at x, k in {Rayleigh, Mie}. Rayleigh has chi = (1, 0, 0.1),
// so its part is exact with l <= 2 (for a zonal field); Mie's forward peak has higher
// moments, which are dropped. The moments are computed as Hillaire computes L_2nd, on the
// same rays, with two corrections:
//  * The first scattering uses the real phase functions p_k(w . s) (Hillaire uses p_u
//    there too), so L'(x, w) is the single-scattered sky as seen from x; the sums along
//    each ray are kept per constituent and the phases applied once the ray is done.
//  * Light of order n + 1 arriving from w is, in Hillaire's local approximation, the
//    order-n mean radiance m_n re-emitted isotropically along the ray: m_n f(w), with
//    f(w) = int_w T sigma_s dt, plus where the ray meets the ground, the ground lit by
//    that isotropic field (irradiance pi m_n) seen through T_g: albedo m_n T_g. So
//      sum over orders >= 2 of the arriving light = Psi_ms f'(w),  f' = f + albedo T_g,
//    whose mean is f_ms' Psi_ms (Hillaire's f_ms plus the ground term, which he leaves
//    out; without it the orders >= 3 come out ~18 % low at 440 nm), and whose Legendre
//    moments are those of f'. Summing:
//      a_0 = Psi_ms = <L'> / (1 - <f'>),
//      a_l = (2l + 1) (<L' P_l> + Psi_ms <f' P_l>),   l = 1, 2,
//    <.> the mean over the sphere (<P_l^2> = 1 / (2l + 1)).
// The sphere integrals use Gauss-Legendre cosines, 4 per hemisphere (the field is
// sharp at the horizon, mu = 0, which Hillaire's uniform strata sample poorly), times 4
// azimuth strata over [0, pi] (the field is symmetric about the sun's vertical plane),
// 32 directions in all at Hillaire's 20 steps per ray.
//
// The error of the extended term against the reference, and of the lut method as a whole,
// is in docs/validation.md ("Multiple-scattering LUT"); the field's azimuthal structure
// about the sun (harmonics in cos(phi), cos(2 phi)) is left out: it moves the total
// radiance very little.
//
// Positivity. The truncated series can undershoot: a strongly forward Mie phase looking
// into the dark side of a lopsided field (hazy and polluted air at the ground with the sun
// just set, looking down; the top of Mars's dusty air, looking up) gets a negative (*) at
// some texels (down to -0.3 times the isotropic term), which no radiance can be. The
// source is therefore clamped at zero texel by texel, before the bilinear lookup, which
// keeps every lookup >= 0 and changes nothing where (*) is positive (every texel of
// bruneton2017, whose smallest (*) over view cosines -1, -0.5, ..., 1 is 0.15 times the
// isotropic term). Limiting the
// moments so that the truncated field itself stays >= 0 would also do, but it flattens
// the horizon peak near the ground and costs accuracy (docs/validation.md).
//
// The sky's two hemispheres. A cloud lit by this field (clouds/illumination.hpp) is lit
// from above by the sky and from below by the ground and the air over it, which a cloud's
// base sees far dimmer than its top sees the sky. The same sums split by the sign of mu_w
// give the field's mean over each hemisphere: with 1_up the indicator of mu_w > 0,
//   L_above = 2 (<L' 1_up> + Psi_ms <f' 1_up>),   L_below = 2 Psi_ms - L_above,
// a fourth texture (L_above; L_below follows, so the two always average to Psi_ms). The
// truncated series would give a_0 +- a_1 / 2 instead, which drops every odd moment above 1.
//
// Cost: four 32 x 32 textures instead of one (the fourth, L_above, for clouds), filled by
// the same loop (one more sum per step and pair, and the phases once per ray and pair). At lookup (*) takes
// three texels at one coordinate, and the weights sigma_k chi_kl P_l(mu_v) depend on the step alone, so a
// sky-view row combines the three texel rows once per step and each view does one lookup.
#pragma once

#include <vector>

#include "welkin/atmosphere/transmittance_lut.hpp"

namespace welkin {

class MultiScatteringLut {
public:
    // directions_sqrt: even; directions_sqrt / 2 Gauss-Legendre cosines per hemisphere
    // times directions_sqrt / 2 azimuths over [0, pi] (Hillaire's 8 x 8 = 64 directions,
    // halved by the symmetry about the sun's vertical plane).
    MultiScatteringLut(const AtmosphereBatch& batch, const TransmittanceLut& transmittance, int size,
                       int directions_sqrt = 8, int steps = 20);

    // Psi_ms = a_0, the mean multiply-scattered radiance per unit sun illuminance (sr^-1).
    Spectrum4 psi(double r, double mu_s) const {
        const float u = texcoord_from_unit(float(0.5 * (mu_s + 1.0)), texture_.width());
        const float v =
            texcoord_from_unit(float(clamp01((r - bottom_) / (top_ - bottom_))), texture_.height());
        return texture_.sample(u, v);
    }

    // The field's mean over the upper and the lower hemisphere about the local zenith
    // (sr^-1 per unit sun illuminance; see "The sky's two hemispheres"); their mean is psi.
    void hemispheres(double r, double mu_s, Spectrum4& above, Spectrum4& below) const {
        const float u = texcoord_from_unit(float(0.5 * (mu_s + 1.0)), texture_.width());
        const float v = v_at_radius(r);
        above = upper_.sample(u, v);
        below = glm::max(2.0f * texture_.sample(u, v) - above, Spectrum4(0.0f));
    }

    // psi with the radius-only part (the v coordinate) computed once.
    float v_at_radius(double r) const {
        return texcoord_from_unit(float(clamp01((r - bottom_) / (top_ - bottom_))), texture_.height());
    }
    Spectrum4 psi(float v, double mu_s) const {
        return texture_.sample(texcoord_from_unit(float(0.5 * (mu_s + 1.0)), texture_.width()), v);
    }

    // Weights of a_1 and a_2 in (*) for a point with scattering coefficients sigma_R,
    // sigma_M and a view of zenith cosine mu_v there (a_0's weight is sigma_R + sigma_M).
    void source_weights(const Spectrum4& sigma_R, const Spectrum4& sigma_M, double mu_v, Spectrum4& w1,
                        Spectrum4& w2) const {
        const float p2 = float(0.5 * (3.0 * mu_v * mu_v - 1.0));
        w1 = sigma_M * float(mie_chi1_ * mu_v);
        w2 = (sigma_R * float(rayleigh_phase_moment(2)) + sigma_M * float(mie_chi2_)) * p2;
    }

    // The multiple-scattering source J_ms of (*) per unit sun illuminance (m^-1 sr^-1) at
    // the radius of texture row coordinate v, sun zenith cosine mu_s: w0 = sigma_R + sigma_M,
    // w1, w2 from source_weights. The three textures share one bilinear coordinate; the
    // source is clamped at zero at each sun-angle texel (see Positivity), after the
    // interpolation in r, exactly as source_row does.
    Spectrum4 source(float v, double mu_s, const Spectrum4& w0, const Spectrum4& w1,
                     const Spectrum4& w2) const {
        const int n = texture_.width(), m = texture_.height();
        const float u = texcoord_from_unit(float(0.5 * (mu_s + 1.0)), n);
        const float x = std::clamp(u * float(n) - 0.5f, 0.0f, float(n - 1));
        const float y = std::clamp(v * float(m) - 0.5f, 0.0f, float(m - 1));
        const int i = std::min(int(x), n - 2), j = std::min(int(y), m - 2);
        const float fx = x - float(i), fy = y - float(j);
        // As source_row: interpolate in r, combine, clamp, then interpolate in mu_s.
        const auto combined = [&](int ii) {
            const auto lerp_r = [&](const Texture2D& t) {
                return t.at(ii, j) + fy * (t.at(ii, j + 1) - t.at(ii, j));
            };
            return glm::max(w0 * lerp_r(texture_) + w1 * lerp_r(dipole_) + w2 * lerp_r(quadrupole_),
                            Spectrum4(0.0f));
        };
        const Spectrum4 c0 = combined(i);
        return c0 + fx * (combined(i + 1) - c0);
    }

    // The texel coordinate of mu_s in a row of the textures, x = (mu_s + 1) / 2 (width - 1),
    // which is u * width - 0.5 for the u of psi(v, mu_s).
    float texel_x(float mu_s) const { return 0.5f * (mu_s + 1.0f) * float(texture_.width() - 1); }

    // source() for many sun angles at one radius and one set of weights: the three rows
    // at v_at_radius(r), interpolated in r and combined with w0, w1, w2 into `buffer`
    // (width texels), returned as a Row whose sample(texel_x(mu_s)) is source(v, mu_s, ...).
    // A step of a sky-view row (inscatter_row) costs one combination and then one linear
    // lookup per view, as the isotropic term did.
    Texture2D::Row source_row(double r, const Spectrum4& w0, const Spectrum4& w1, const Spectrum4& w2,
                              std::vector<Spectrum4>& buffer) const {
        const Texture2D::Row a0 = texture_.row(v_at_radius(r));
        const Texture2D::Row a1 = dipole_.row(v_at_radius(r)), a2 = quadrupole_.row(v_at_radius(r));
        const int n = texture_.width();
        buffer.resize(std::size_t(n));
        const float fy = a0.fy;
        for (int i = 0; i < n; ++i) {
            const Spectrum4 c0 = a0.lo[i] + fy * (a0.hi[i] - a0.lo[i]);
            const Spectrum4 c1 = a1.lo[i] + fy * (a1.hi[i] - a1.lo[i]);
            const Spectrum4 c2 = a2.lo[i] + fy * (a2.hi[i] - a2.lo[i]);
            buffer[std::size_t(i)] = glm::max(w0 * c0 + w1 * c1 + w2 * c2, Spectrum4(0.0f));
        }
        return {buffer.data(), buffer.data(), 0.0f, n - 1};
    }

    const Texture2D& texture() const { return texture_; }        // a_0 = Psi_ms
    const Texture2D& dipole() const { return dipole_; }          // a_1
    const Texture2D& quadrupole() const { return quadrupole_; }  // a_2
    const Texture2D& upper() const { return upper_; }            // L_above

private:
    void store_row(int j, int n_phi, const std::vector<Spectrum4>& m0, const std::vector<Spectrum4>& m1,
                   const std::vector<Spectrum4>& m2, const std::vector<Spectrum4>& m_up, const Spectrum4& f0,
                   const Spectrum4& f1, const Spectrum4& f2, const Spectrum4& f_up);

    double bottom_, top_;
    double mie_chi1_, mie_chi2_;
    Texture2D texture_, dipole_, quadrupole_, upper_;
};

}  // namespace welkin
