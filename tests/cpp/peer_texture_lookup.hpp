// SPDX-License-Identifier: Apache-2.0
// Bruneton 2017's 4D scattering-texture lookup for a camera on the ground, emulated: which
// texels GetSkyRadiance reads, with which weights, and the geometry each texel stands for.
// (precomputed_atmospheric_scattering, atmosphere/functions.glsl,
// GetScatteringTextureUvwzFromRMuMuSNu, GetRMuMuSNuFromScatteringTextureFragCoord and
// GetCombinedScattering; read for the mapping, nothing copied.) Texture size 8 (nu) x 32
// (mu_s) x 128 (mu) x 32 (r). Written out for r = R (camera on the ground), where the r
// coordinate falls exactly on the first texel centre and the view rays above the horizon
// use the upper half of the mu axis:
//  * mu: texel i (0..63) of the upper half holds the ray whose distance to the top is
//    d_i = d_min + (i / 63) (d_max - d_min), d_min = top - R, d_max = H = sqrt(top^2 - R^2),
//    i.e. mu_i = (H^2 - d_i^2) / (2 R d_i). Texel 0 is the zenith; texel 1 is already
//    39 degrees from it.
//  * mu_s: texel k (0..31) holds x = k / 31 of x(mu_s) = max(1 - a / A, 0) / (1 + a),
//    a = (d_s - d_min) / (d_max - d_min) with d_s the distance to the top along the sun
//    ray from the ground, A = -2 mu_s_min R / (d_max - d_min); mu_s_min is the cosine of
//    the model's largest sun zenith angle (102 degrees in the demo; 120 degrees changes the
//    emulated orders 2-4 by under 0.4 % of L at the table's views, measured).
//  * nu: slice l (0..7) holds nu_l = -1 + 2 l / 7, CLAMPED to the range that is possible for
//    the texel's mu and mu_s, [mu mu_s - s, mu mu_s + s], s = sqrt((1 - mu^2)(1 - mu_s^2)).
//    At the zenith texel that range is the single value mu_s: every slice of it holds the
//    same geometry.
// Lookups interpolate linearly on each axis. The multiple-scattering part of the texture
// holds L_ms(texel) / p_R(nu_texel) (reference/model.cc divides by the Rayleigh phase of
// the texel's clamped nu) and GetSkyRadiance multiplies the interpolated value by p_R(nu)
// of the view, so the peer's orders >= 2 for a view are
//
//   L_ms,peer(mu, mu_s, nu) = p_R(nu) sum_texels w L_ms(texel) / p_R(nu_texel).          (1)
//
// Where the texels' clamped nu differ from the view's, p_R(nu) / p_R(nu_texel) is not 1:
// next to the zenith texel, whose nu is mu_s whatever the slice, a view 30 degrees up
// towards a sun 30 degrees from the zenith gets its zenith share scaled by
// p_R(1) / p_R(0.866) = 1.14, the view opposite by p_R(0.5) / p_R(0.866) = 0.71.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/phase.hpp"

namespace welkin::test {

struct PeerTexel {
    double mu, mu_s, nu;  // the geometry the texel was computed for (nu clamped)
    double weight;        // its weight in the lookup
};

class PeerGroundTexture {
public:
    explicit PeerGroundTexture(const Atmosphere& atm, double max_sun_zenith_deg = 102.0)
        : R_(atm.bottom_radius_m), top_(atm.top_radius_m) {
        H_ = std::sqrt(top_ * top_ - R_ * R_);
        d_min_ = top_ - R_;
        A_ = -2.0 * std::cos(max_sun_zenith_deg * kDegree) * R_ / (H_ - d_min_);
    }

    // The 8 texels read for a view (mu >= 0) from the ground, sun at mu_s, view-sun nu.
    std::vector<PeerTexel> texels(double mu, double mu_s, double nu) const {
        double wm, ws, wn;
        const int i = cell(x_mu(mu) * 63.0, 62, wm);
        const int k = cell(x_mu_s(mu_s) * 31.0, 30, ws);
        const int l = cell((nu + 1.0) / 2.0 * 7.0, 6, wn);
        std::vector<PeerTexel> out;
        for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b)
                for (int c = 0; c < 2; ++c) {
                    const double m = mu_of(i + a), s = mu_s_of(k + b);
                    const double spread = std::sqrt(std::max(0.0, (1.0 - m * m) * (1.0 - s * s)));
                    const double n = std::clamp(-1.0 + 2.0 * (l + c) / 7.0, m * s - spread, m * s + spread);
                    out.push_back({m, s, n, (a ? wm : 1 - wm) * (b ? ws : 1 - ws) * (c ? wn : 1 - wn)});
                }
        return out;
    }

    // (1): the peer's lookup of a field f(texel) stored divided by p_R(nu_texel).
    template <class F>
    auto rayleigh_normalised_lookup(double mu, double mu_s, double nu, F&& f) const {
        auto texel_list = texels(mu, mu_s, nu);
        auto first = f(texel_list[0]);
        for (auto& x : first) x = 0.0;
        for (const PeerTexel& t : texel_list) {
            const auto v = f(t);
            for (std::size_t c = 0; c < v.size(); ++c)
                first[c] += t.weight * v[c] * rayleigh_phase(nu) / rayleigh_phase(t.nu);
        }
        return first;
    }

private:
    static int cell(double x, int last, double& w) {
        const int i = std::clamp(int(std::floor(x)), 0, last);
        w = std::clamp(x - i, 0.0, 1.0);
        return i;
    }
    double x_mu(double mu) const {
        const double d = -R_ * mu + std::sqrt(R_ * R_ * (mu * mu - 1.0) + top_ * top_);
        return (d - d_min_) / (H_ - d_min_);
    }
    double mu_of(int i) const {
        const double d = d_min_ + i / 63.0 * (H_ - d_min_);
        return std::clamp((H_ * H_ - d * d) / (2.0 * R_ * d), -1.0, 1.0);
    }
    double x_mu_s(double mu_s) const {
        const double d = -R_ * mu_s + std::sqrt(R_ * R_ * (mu_s * mu_s - 1.0) + top_ * top_);
        const double a = (d - d_min_) / (H_ - d_min_);
        return std::max(1.0 - a / A_, 0.0) / (1.0 + a);
    }
    double mu_s_of(int k) const {
        const double x = k / 31.0;
        const double a = (A_ - x * A_) / (1.0 + x * A_);
        const double d = d_min_ + std::min(a, A_) * (H_ - d_min_);
        return std::clamp((H_ * H_ - d * d) / (2.0 * R_ * d), -1.0, 1.0);
    }

    double R_, top_, H_, d_min_, A_;
};

}  // namespace welkin::test
