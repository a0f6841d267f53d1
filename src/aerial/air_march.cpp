// SPDX-License-Identifier: Apache-2.0
// The shared march of aerial perspective (air_march.hpp); the integral it computes is
// derived in aerial_perspective.cpp's opening comment.
#include "air_march.hpp"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/base/math.hpp"
#include "welkin/base/simd.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/gamut.hpp"

namespace welkin::aerial_march {

AirRay air_ray(const AerialView& view, const CameraRays::Ray& ray, const glm::dvec3& sun) {
    return {ray.origin - view.planet_centre(), ray.direction, sun};
}

void march_segment(const AtmosphereLuts::Batch& b, const AirRay& ray, float rayleigh_p, float mie_p,
                   double t0, double t1, int n, Spectrum4& L, Spectrum4& T) {
    if (!(t1 > t0)) return;
    const AtmosphereBatch& medium = b.medium;
    const double R = medium.bottom_radius(), top = medium.top_radius();
    const double dt = (t1 - t0) / double(n);
    const float dtf = float(dt);
    for (int i = 0; i < n; ++i) {
        const double t = t0 + (double(i) + 0.5) * dt;
        const glm::dvec3 x = ray.p0 + t * ray.d;
        const double r = glm::length(x);
        if (r >= top) continue;  // no air
        const MediumSample m = medium.sample(r - R);
        const double r_lookup = std::max(r, R);  // below the ground sphere: the ground's air
        const double mu_s = clamp_cosine(glm::dot(x, ray.sun) / r);
        const Spectrum4 sun_t = b.transmittance.to_sun(r_lookup, mu_s);
        const Spectrum4 psi = b.multiscattering.psi(r_lookup, mu_s);
        const Float4 source =
            to_float4(sun_t * (m.rayleigh_scattering * rayleigh_p + m.mie_scattering * mie_p) +
                      (m.rayleigh_scattering + m.mie_scattering) * psi);
        const Float4 extinction = to_float4(m.extinction);
        const Float4 T_seg = exp_nonpositive(-extinction * dtf);
        // (1 - T_seg) / sigma_t, or dt where the step holds no extinction.
        const Float4 tiny = {1e-12f, 1e-12f, 1e-12f, 1e-12f}, one = {1.0f, 1.0f, 1.0f, 1.0f};
        const Float4 thin = extinction > tiny ? extinction : one;
        const Float4 w = extinction > tiny ? (one - T_seg) / thin : Float4{dtf, dtf, dtf, dtf};
        L += to_vec4(to_float4(T) * w * source);
        T *= to_vec4(T_seg);
    }
}

PassColour::PassColour(const Atmosphere& atm, double exposure, ColorSpace space)
    : channels_(atm.wavelengths_nm.size()) {
    const SpectrumToRgb sky(atm.wavelengths_nm, -3.0, space), sun(atm.wavelengths_nm, 0.0, space);
    luminance_ = sky.luminance_weights();
    const std::vector<float> solar(atm.solar_irradiance.begin(), atm.solar_irradiance.end());
    const std::array<double, 3> white = sun.convert(solar);
    sky_.resize(3 * channels_);
    sun_.resize(3 * channels_);
    for (std::size_t k = 0; k < 3; ++k)
        for (std::size_t c = 0; c < channels_; ++c) {
            sky_[k * channels_ + c] = sky.matrix()[k * channels_ + c] * exposure;
            sun_[k * channels_ + c] =
                white[k] > 0.0 ? sun.matrix()[k * channels_ + c] * double(solar[c]) / white[k] : 0.0;
        }
}

void PassColour::convert(const float* L, const float* T, float* L3, float* T3) const {
    for (std::size_t k = 0; k < 3; ++k) {
        double l = 0.0, t = 0.0;
        for (std::size_t c = 0; c < channels_; ++c) {
            l += sky_[k * channels_ + c] * double(L[c]);
            t += sun_[k * channels_ + c] * double(T[c]);
        }
        L3[k] = float(l);
        T3[k] = float(clamp01(t));
    }
    if (L3[0] < 0.0f || L3[1] < 0.0f || L3[2] < 0.0f)  // no negative in-scattering (gamut.hpp)
        gamut_map(L3, 1, luminance_);
}

void SliceMarcher::march(const AirRay& ray, std::span<const double> distances, float* L3, float* T3) {
    const std::size_t C = colour_.channels(), n = distances.size();
    L_.resize(n * C);
    T_.resize(n * C);
    const float nu = float(clamp_cosine(glm::dot(ray.d, ray.sun)));
    for (const auto& b : luts_.batches()) {
        const float rp = b->medium.rayleigh_phase(nu), mp = b->medium.mie_phase(nu);
        Spectrum4 Ls(0.0f), Ts(1.0f);
        double t_prev = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
            march_segment(*b, ray, rp, mp, t_prev, distances[k], steps_, Ls, Ts);
            t_prev = distances[k];
            store_channels(Ls * b->medium.solar_irradiance(), b->medium.channel_count(),
                           &L_[k * C + b->medium.first_channel()]);
            store_channels(Ts, b->medium.channel_count(), &T_[k * C + b->medium.first_channel()]);
        }
    }
    for (std::size_t k = 0; k < n; ++k) colour_.convert(&L_[k * C], &T_[k * C], L3 + 3 * k, T3 + 3 * k);
}

float optical_depth_of(float T) {
    return T > 0.0f ? std::min(-std::log(T), kMaxOpticalDepth) : kMaxOpticalDepth;
}

}  // namespace welkin::aerial_march
