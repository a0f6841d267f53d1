// Multiple-scattering LUT (Hillaire 2020, "A Scalable and Production Ready Sky and
// Atmosphere Rendering Technique", sec. 5.5, 32 x 32 texels).
//
// For a point at radius r lit by the sun at zenith cosine mu_s, Hillaire approximates all
// scattering orders >= 2 by assuming that the light reaching the point after two or more
// bounces comes equally from every direction, and that each order carries a constant
// fraction f_ms of the previous one. With unit sun illuminance and an isotropic phase
// p_u = 1 / (4 pi):
//   L_2nd = integral over the sphere of L'(x, w) p_u dw, where L' is the single-scattered
//           radiance along w plus the sun light the ground reflects (Lambertian),
//   f_ms  = integral over the sphere of (integral along w of T sigma_s dt) p_u dw,
//   Psi_ms = L_2nd (1 + f_ms + f_ms^2 + ...) = L_2nd / (1 - f_ms)          (eq. 9)
// and the multiple-scattering radiance a point scatters towards the viewer is
// sigma_s(x) Psi_ms(r, mu_s) E_sun (eq. 10). The sphere integrals use 64 directions
// (8 x 8 strata, as in the paper,
// folded to 8 x 4 by the symmetry about the sun's vertical plane) and 20 steps per ray.
#pragma once

#include "welkin/transmittance_lut.hpp"

namespace welkin {

class MultiScatteringLut {
public:
    MultiScatteringLut(const AtmosphereBatch& batch, const TransmittanceLut& transmittance,
                       int size, int directions_sqrt = 8, int steps = 20);

    // Psi_ms per unit sun illuminance (sr^-1).
    Spectrum4 psi(double r, double mu_s) const {
        const float u = texcoord_from_unit(float(0.5 * (mu_s + 1.0)), texture_.width());
        const float v = texcoord_from_unit(float(clamp01((r - bottom_) / (top_ - bottom_))), texture_.height());
        return texture_.sample(u, v);
    }

    // psi with the radius-only part (the v coordinate) computed once.
    float v_at_radius(double r) const {
        return texcoord_from_unit(float(clamp01((r - bottom_) / (top_ - bottom_))), texture_.height());
    }
    Spectrum4 psi(float v, double mu_s) const {
        return texture_.sample(texcoord_from_unit(float(0.5 * (mu_s + 1.0)), texture_.width()), v);
    }

    // psi for many sun angles at one radius (Texture2D::Row): the row of v_at_radius(r),
    // and the texel coordinate of mu_s, x = (mu_s + 1) / 2 (width - 1), which is
    // u * width - 0.5 for the u of psi(v, mu_s).
    Texture2D::Row row_at_radius(double r) const { return texture_.row(v_at_radius(r)); }
    float texel_x(float mu_s) const { return 0.5f * (mu_s + 1.0f) * float(texture_.width() - 1); }

    const Texture2D& texture() const { return texture_; }

private:
    double bottom_, top_;
    Texture2D texture_;
};

}  // namespace welkin
