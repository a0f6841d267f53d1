// SPDX-License-Identifier: Apache-2.0
// The delta-Eddington slab along the sun line; see clouds/diffusion.hpp.
#include "welkin/clouds/diffusion.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "welkin/base/math.hpp"

namespace welkin {

namespace {

// The conservative slab, phi = A + B z + C e^{-z/mu0}, C = -3 mu0^2, given the beam's
// e^{-z/mu0} and e^{-Z/mu0} (shared by every inclination along one sun line: z / mu0 and
// Z / mu0 are the sun line's own depths); the faces give
//   A - (2/3) B = -C (1 + q),   A + B (Z + 2/3) = -C e^{-Z/mu0} (1 - q),   q = 2 / (3 mu0).
DiffuseField conservative_slab(double Z, double z, double mu0, double beam_z, double beam_Z) {
    const double q = 2.0 / (3.0 * mu0);
    const double C = -3.0 * mu0 * mu0;
    const double B = -C * (beam_Z * (1.0 - q) - (1.0 + q)) / (Z + 4.0 / 3.0);
    const double A = (2.0 / 3.0) * B - C * (1.0 + q);
    return {A + B * z + C * beam_z, -(B - C / mu0 * beam_z) / 3.0};
}

constexpr double kConservative = 3e-12;  // k^2 below this: albedo' = 1 to 1e-12

}  // namespace

DiffuseField eddington_slab(double Z, double z, double albedo, double mu0, double leak) {
    Z = std::max(Z, 0.0);
    z = std::clamp(z, 0.0, Z);
    const double k2 = 3.0 * (1.0 - albedo) + leak;
    if (k2 < kConservative) return conservative_slab(Z, z, mu0, std::exp(-z / mu0), std::exp(-Z / mu0));
    // phi = A e^{-kz} + B e^{-k(Z-z)} + P(z), P a particular solution; the faces give
    //   A p + B m = -(P(0) - (2/3) P'(0)),   A m + B p = -(P(Z) + (2/3) P'(Z)),
    //   p = 1 + 2k/3, m = (1 - 2k/3) e^{-kZ}.
    // P = C e^{-z/mu0}, C = 3 albedo mu0^2 / (k^2 mu0^2 - 1), except at the resonance
    // k mu0 = 1, where P = D z e^{-z/mu0}, D = 3 albedo mu0 / 2 (P'' - k^2 P = -(2 D / mu0)
    // e^{-z/mu0} there). C's rounding grows as 1 / |k^2 mu0^2 - 1|, the resonant form's
    // error as |k^2 mu0^2 - 1|: the switch at 1e-8 keeps both near 1e-8.
    const double km2 = k2 * mu0 * mu0;
    const double k = std::sqrt(k2);
    const bool resonant = std::abs(km2 - 1.0) < 1e-8;
    const double C = resonant ? 1.5 * albedo * mu0 : 3.0 * albedo * mu0 * mu0 / (km2 - 1.0);
    const auto particular = [&](double x, double& P, double& dP) {
        const double e = std::exp(-x / mu0);
        if (resonant) {
            P = C * x * e;
            dP = C * e * (1.0 - x / mu0);
        } else {
            P = C * e;
            dP = -C / mu0 * e;
        }
    };
    double P0, dP0, PZ, dPZ, Pz, dPz;
    particular(0.0, P0, dP0);
    particular(Z, PZ, dPZ);
    particular(z, Pz, dPz);
    const double p = 1.0 + 2.0 * k / 3.0, m = (1.0 - 2.0 * k / 3.0) * std::exp(-k * Z);
    const double r1 = -(P0 - (2.0 / 3.0) * dP0), r2 = -(PZ + (2.0 / 3.0) * dPZ);
    const double det = p * p - m * m;  // > 0: p > |m|
    const double A = (p * r1 - m * r2) / det, B = (p * r2 - m * r1) / det;
    const double ea = std::exp(-k * z), eb = std::exp(-k * (Z - z));
    const double phi = A * ea + B * eb + Pz;
    const double dphi = -k * A * ea + k * B * eb + dPz;
    return {phi, -dphi / 3.0};
}

SimilarityScaling::SimilarityScaling(double a, double g) {
    forward = std::max(g, 0.0);
    depth_scale = 1.0 - a * forward;
    albedo = depth_scale > 0.0 ? (1.0 - forward) * a / depth_scale : 1.0;
}

double sun_source(const SimilarityScaling& sim, double tau_sun, double tau_anti, double tau_side, double nu,
                  double g, double p, double p2) {
    const double single = std::exp(-tau_sun);
    const double ts = sim.depth_scale * tau_sun, T = sim.depth_scale * (tau_sun + tau_anti);
    // The sides (header): the fundamental transverse mode's buckling across the chord's
    // scaled width W' between extrapolated boundaries, B = pi / (W' + 4/3).
    const double Bw = std::isfinite(tau_side) ? kPi / (sim.depth_scale * tau_side + 4.0 / 3.0) : 0.0;
    const double leak = Bw * Bw;
    // The orientation average (see the header): int_0^1 2 mu0 f(mu0) dmu0 = int_0^1 f(sqrt(v)) dv,
    // by 3-point Gauss-Legendre in v = mu0^2 (exact for f polynomial of degree 5 in v).
    // Nodes v = 1/2 -+ sqrt(3/5) / 2, 1/2; weights 5/18, 8/18, 5/18.
    static constexpr std::array<double, 3> w = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
    // mu = sqrt(v):
    static constexpr std::array<double, 3> mu = {0.3357106870197288, 0.7071067811865476, 0.9419651451198934};
    const double beam_t = std::exp(-ts), beam_T = std::exp(-T);  // the scaled beam
    // The slab's diffuse source towards the viewer at inclination i, with the leak k2_extra.
    const auto slab = [&](int i, double k2_extra) {
        const DiffuseField d = 3.0 * (1.0 - sim.albedo) + k2_extra < kConservative
                                   ? conservative_slab(mu[i] * T, mu[i] * ts, mu[i], beam_t, beam_T)
                                   : eddington_slab(mu[i] * T, mu[i] * ts, sim.albedo, mu[i], k2_extra);
        return std::max(0.0, d.fluence + 3.0 * g * d.flux * mu[i] * nu);
    };
    // The higher modes' share at depth t' (the header's blend); below 1e-4 of the difference
    // it is left out.
    const double near = std::exp(-3.0 * Bw * ts);
    double diffuse = 0.0;
    for (int i = 0; i < 3; ++i) {
        double v = slab(i, leak);
        if (leak > 0.0 && near > 1e-4) v += (slab(i, 0.0) - v) * near;
        diffuse += w[i] * v;
    }
    const double forward = (beam_t - single) * p2;
    return single * p + forward + diffuse / (4.0 * kPi);
}

}  // namespace welkin
