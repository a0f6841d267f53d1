// SPDX-License-Identifier: Apache-2.0
// Transmittance LUT: T(r, mu) from a point at radius r along zenith cosine mu to the top
// of the atmosphere, for rays that do not hit the ground (Bruneton 2017 sec. 4.1;
// Hillaire 2020 sec. 4, 256 x 64 texels).
//
// Parametrisation (Bruneton 2017, GetTransmittanceTextureUvFromRMu): with
// H = sqrt(top^2 - R^2) and rho = sqrt(r^2 - R^2), x_r = rho / H and
// x_mu = (d - d_min) / (d_max - d_min), where d is the distance to the top, d_min = top - r
// and d_max = rho + H. This spends texels where transmittance varies: near the horizon.
//
// Transmittance between two points follows from two lookups (Bruneton 2017,
// GetTransmittance): T(p -> q) = T(p) / T(q) for rays going up to the top, and
// T(q, -mu_q) / T(p, -mu_p) for rays going down to the ground.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/texture2d.hpp"
#include "welkin/base/math.hpp"

namespace welkin {

// Fraction of the sun's disc (angular radius `angular_radius`) above a horizon of zenith
// cosine cos_horizon: 0 when the sun is set, 1 when risen, smooth in between (a smoothstep
// in the sine of the elevation across the disc, as Bruneton 2017's GetTransmittanceToSun).
inline double sun_visible_fraction_at(double mu_s, double cos_horizon, double angular_radius) {
    const double x = std::clamp((mu_s - cos_horizon + angular_radius) / (2.0 * angular_radius), 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// The horizon of a point at radius r above a ground sphere of radius R, given
// rho = sqrt(r^2 - R^2): zenith cosine -sqrt(1 - R^2 / r^2) = -rho / r (0 at or below the
// ground, where rho is 0).
inline double horizon_cosine(double r, double rho) { return rho > 0.0 ? -rho / r : 0.0; }

// sun_visible_fraction_at for a point at radius r.
inline double sun_visible_fraction(double bottom_radius, double r, double mu_s, double angular_radius) {
    const double rho = safe_sqrt((r - bottom_radius) * (r + bottom_radius));
    return sun_visible_fraction_at(mu_s, horizon_cosine(r, rho), angular_radius);
}

class TransmittanceLut {
public:
    TransmittanceLut(const AtmosphereBatch& batch, int width, int height, int steps = 32);

    // Transmittance to the top (mu clamped to the horizon for rays that would hit the ground).
    Spectrum4 to_top(double r, double mu) const;

    // Sun transmittance at (r, mu_s), with the planet's shadow: the fraction of the sun disc
    // above the horizon, linear in the sine of the elevation across the disc (Bruneton
    // 2017, GetTransmittanceToSun).
    // (rho, the radius's square root, is formed once for the horizon and the texel row; inline:
    // the marches look the sun up at every sample.)
    Spectrum4 to_sun(double r, double mu_s) const {
        const double rho = safe_sqrt((r - bottom_) * (r + bottom_));
        const double fraction = sun_visible_fraction_at(mu_s, horizon_cosine(r, rho), sun_angular_radius_);
        if (fraction <= 0.0) return Spectrum4(0.0f);
        float u, v;
        if (r <= top_)
            uv_from_r_rho_mu(r, rho, mu_s, u, v);
        else
            uv_from_r_mu(top_, mu_s, u, v);
        return texture_.sample(u, v) * float(fraction);
    }

    // The parts of a sun lookup that depend on the radius alone, computed once in double
    // for many sun angles at the same radius (the marches evaluate a whole row of the
    // sky-view LUT, or every sun angle of the multiple-scattering LUT, at each sample).
    // What varies with the sun angle is then done in float without losing digits. The
    // distance to the top, d = -r mu_s + sqrt(r^2 mu_s^2 + K) with K = top^2 - r^2 =
    // (top - r)(top + r) >= 0, cancels for mu_s > 0 and is written there as
    // d = K / (r mu_s + sqrt(r^2 mu_s^2 + K)); for mu_s < 0 both terms are positive. K and
    // d_min = top - r, where digits matter, are rounded from double; r itself in float is
    // off by at most 0.25 m (4e-8 relative), which only scales r mu_s. The texel
    // coordinate is x = (d - d_min) / (d_max - d_min) (width - 1) (Texture2D::Row), and the
    // visible fraction's smoothstep argument (sun_visible_fraction) is linear in mu_s.
    struct AtRadius {
        double r;  // clamped to the top
        float r_f, top_k, d_min, x_scale, fraction_scale, fraction_offset;
        Texture2D::Row row;
    };
    AtRadius at_radius(double r) const;

    // The two halves of a sun lookup at one radius: the texel coordinate and the visible
    // fraction (arithmetic only, so loops over many sun angles vectorise), then the fetch.
    // (Both forms of d are computed and one selected, so that the loop has no branch.)
    static void sun_lookup(const AtRadius& at, float mu_s, float& x, float& fraction) {
        const float s = clamp_value(mu_s * at.fraction_scale + at.fraction_offset, 0.0f, 1.0f);
        fraction = s * s * (3.0f - 2.0f * s);
        const float rm = at.r_f * mu_s;
        const float q = std::sqrt(rm * rm + at.top_k);
        const float d_up = at.top_k / max_value(rm + q, 1e-30f), d_down = q - rm;
        x = ((rm >= 0.0f ? d_up : d_down) - at.d_min) * at.x_scale;
    }
    static Spectrum4 to_sun(const AtRadius& at, float mu_s) {
        float x, fraction;
        sun_lookup(at, mu_s, x, fraction);
        return at.row.sample(x) * fraction;
    }

    const Texture2D& texture() const { return texture_; }

    // (u, v) of (r, mu) and back; exposed for tests.
    void uv_from_r_mu(double r, double mu, float& u, float& v) const;
    void r_mu_from_uv(float u, float v, double& r, double& mu) const;

private:
    // uv_from_r_mu with rho = sqrt(r^2 - bottom^2) given.
    void uv_from_r_rho_mu(double r, double rho, double mu, float& u, float& v) const {
        const double d = distance_to_top(r, mu, top_);
        const double d_min = top_ - r, d_max = rho + H_;
        const double x_mu = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
        u = texcoord_from_unit(float(clamp01(x_mu)), texture_.width());
        v = texcoord_from_unit(float(clamp01(rho / H_)), texture_.height());
    }

    double bottom_, top_, H_;  // H = sqrt(top^2 - bottom^2)
    float sun_angular_radius_;
    Texture2D texture_;
};

// Optical depth (as a Spectrum4 of tau) along [0, length] of the ray (r, mu), by
// Gauss-Legendre on panels graded towards the lowest altitude; `samples` evaluations, plus
// four for each panel split where the ray crosses a density profile's breakpoint.
// The kernel of the transmittance LUT and of the ray-march method's sun rays. The nodes
// and weights depend on `samples` alone: GradedQuadrature holds them for loops that march
// many rays, march_optical_depth builds them for one.
class GradedQuadrature {
public:
    explicit GradedQuadrature(int samples);
    Spectrum4 optical_depth(const AtmosphereBatch& batch, double r, double mu, double length) const;

private:
    // One graded piece of `panels` 4-point panels: per node, s^2 and the weight
    // w 2 s / panels of the substitution t = len s^2 (transmittance_lut.cpp).
    struct Piece {
        std::vector<double> s2;
        std::vector<float> weight;
    };
    static Piece make_piece(int panels);
    Spectrum4 integrate(const AtmosphereBatch& batch, double r, double mu, double a, double b, bool toward_a,
                        const Piece& piece) const;
    Piece whole_, half_;  // a ray densest at one end; each side of an interior lowest point
};

Spectrum4 march_optical_depth(const AtmosphereBatch& batch, double r, double mu, double length, int samples);

}  // namespace welkin
