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

#include "welkin/texture2d.hpp"

namespace welkin {

class TransmittanceLut {
public:
    TransmittanceLut(const AtmosphereBatch& batch, int width, int height, int steps = 40);

    // Transmittance to the top (mu clamped to the horizon for rays that would hit the ground).
    Spectrum4 to_top(double r, double mu) const;

    // Transmittance over the segment [0, d] of the ray (r, mu).
    Spectrum4 segment(double r, double mu, double d, bool ray_hits_ground) const;

    // Sun transmittance at (r, mu_s), with the planet's shadow: the fraction of the sun disc
    // above the horizon, linear in the sine of the elevation across the disc (Bruneton
    // 2017, GetTransmittanceToSun).
    Spectrum4 to_sun(double r, double mu_s) const;

    // The parts of a sun lookup that depend on the radius alone, computed once for many
    // sun angles at the same radius (the marches evaluate a whole row of the sky-view LUT,
    // or every sun angle of the multiple-scattering LUT, along one ray).
    struct AtRadius {
        double r, cos_horizon, top_disc, d_min, inv_d_range;
        float v;
    };
    AtRadius at_radius(double r) const;
    Spectrum4 to_sun(const AtRadius& at, double mu_s) const {
        const double x = std::clamp((mu_s - at.cos_horizon + sun_angular_radius_) / (2.0 * sun_angular_radius_), 0.0, 1.0);
        if (x <= 0.0) return Spectrum4(0.0f);
        const double d = -at.r * mu_s + std::sqrt(std::max(at.r * at.r * mu_s * mu_s - at.top_disc, 0.0));
        const float x_mu = float(std::clamp((d - at.d_min) * at.inv_d_range, 0.0, 1.0));
        return texture_.sample(texcoord_from_unit(x_mu, texture_.width()), at.v) * float(x * x * (3.0 - 2.0 * x));
    }

    const Texture2D& texture() const { return texture_; }

    // (u, v) of (r, mu) and back; exposed for tests.
    void uv_from_r_mu(double r, double mu, float& u, float& v) const;
    void r_mu_from_uv(float u, float v, double& r, double& mu) const;

private:
    double bottom_, top_, H_;  // H = sqrt(top^2 - bottom^2)
    float sun_angular_radius_;
    Texture2D texture_;
};

// Fraction of the sun's disc (angular radius `angular_radius`) above the horizon of a
// point at radius r: 0 when the sun is set, 1 when risen, smooth in between (a smoothstep
// in the sine of the elevation across the disc, as Bruneton 2017's GetTransmittanceToSun).
double sun_visible_fraction(double bottom_radius, double r, double mu_s, double angular_radius);

// Optical depth (as a Spectrum4 of tau) along [0, length] of the ray (r, mu), by
// Gauss-Legendre on panels graded towards the lowest altitude; `samples` evaluations.
// The kernel of the transmittance LUT and of the ray-march method's sun rays.
Spectrum4 march_optical_depth(const AtmosphereBatch& batch, double r, double mu, double length,
                              int samples);

}  // namespace welkin
