// SPDX-License-Identifier: Apache-2.0
// Up to four of an atmosphere's channels, packed for the fast methods.
//
// The LUT and ray-march methods work on four wavelengths at a time in single precision
// (glm::vec4, one SIMD register): the default four channels fill one batch (three would
// leave the fourth lane repeating the third), a spectral atmosphere of 48 wavelengths is
// twelve batches.
// Geometry stays in double (geometry.hpp); radiance and coefficients are float.
//
// Densities are tabulated once per batch: the scattering and extinction coefficients at
// kTableSize radii r evenly spaced in r^2 from the ground to the top, interpolated
// linearly in r^2. A ray's r(t)^2 = (t + r mu)^2 + r^2 (1 - mu^2) is a polynomial in t, so
// a quadrature along a ray finds its table coordinate without a square root, the cost
// that dominated the transmittance LUT's build; an altitude h has r^2 - R^2 = h (2R + h).
// The spacing in altitude, d(r^2) / 2r, varies by only (top - R) / R across the
// atmosphere (0.9 % on Earth, 7.4 m there with 8192 entries). For an exponential layer
// sampled every dh the relative interpolation error is at most dh^2 / (8 H^2) (1 + H / R):
// with 8192 entries over Earth's 60 km and H = 1.2 km it is 4.7e-6 (measured 4.8e-6 with
// the float rounding; tests/cpp/test_atmosphere_batch.cpp).
#pragma once

#include <algorithm>
#include <vector>

#include <glm/common.hpp>
#include <glm/exponential.hpp>
#include <glm/vec4.hpp>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/simd.hpp"

namespace welkin {

using Spectrum4 = glm::vec4;

struct MediumSample {
    Spectrum4 rayleigh_scattering;  // m^-1
    Spectrum4 mie_scattering;       // m^-1
    Spectrum4 extinction;           // m^-1, all constituents
};

class AtmosphereBatch {
public:
    static constexpr int kTableSize = 8192;

    // Channels [first, first + count) of `atmosphere`, count in 1..4.
    AtmosphereBatch(const Atmosphere& atmosphere, std::size_t first, std::size_t count);

    // All batches covering the atmosphere's channels.
    static std::vector<AtmosphereBatch> split(const Atmosphere& atmosphere);

    double bottom_radius() const { return bottom_radius_; }
    double top_radius() const { return top_radius_; }
    std::size_t first_channel() const { return first_; }
    std::size_t channel_count() const { return count_; }

    const Spectrum4& solar_irradiance() const { return solar_irradiance_; }
    const Spectrum4& ground_albedo() const { return ground_albedo_; }
    float sun_angular_radius() const { return sun_angular_radius_; }

    // Coefficients at altitude h (clamped to the atmosphere; zero above its top).
    MediumSample sample(double altitude_m) const {
        const double x = altitude_m * (2.0 * bottom_radius_ + altitude_m) * inv_table_step_;
        if (!(x >= 0.0)) return table_.front();
        if (x >= double(kTableSize - 1)) return altitude_m > thickness_ ? MediumSample{} : table_.back();
        const int i = int(x);
        const float f = float(x - double(i));
        const MediumSample& a = table_[i];
        const MediumSample& b = table_[i + 1];
        return {a.rayleigh_scattering + f * (b.rayleigh_scattering - a.rayleigh_scattering),
                a.mie_scattering + f * (b.mie_scattering - a.mie_scattering),
                a.extinction + f * (b.extinction - a.extinction)};
    }

    // The extinction alone, for loops that compute many table coordinates first
    // (x = (r^2 - R^2) * inv_table_step(), clamped to [0, kTableSize - 1]), given as the
    // entry i = int(x) and the weight f = x - i: a compact table holds, per altitude, the
    // extinction a and its step to the next entry b - a (zero after the last), so that a
    // lookup reads 32 adjacent bytes and does one multiply-add. Equal to
    // sample(altitude).extinction inside the atmosphere (but for rounding).
    double inv_table_step() const { return inv_table_step_; }  // entries per m^2 of r^2
    struct ExtinctionEntry {
        Float4 value, step;
    };
    Float4 extinction_at(int i, float f) const {
        const ExtinctionEntry& e = extinction_[std::size_t(i)];
        return e.value + f * e.step;
    }

    // Radii where a density profile has a kink or a jump (DensityProfile::breakpoints_m of
    // the three constituents, inside the atmosphere; sorted, distinct): quadratures along
    // rays cut their panels there (GradedQuadrature), since a panel across a kink loses
    // Gauss-Legendre's order.
    const std::vector<double>& breakpoint_radii() const { return breakpoint_radii_; }

    // Phase functions at scattering cosine nu (phase.hpp).
    float rayleigh_phase(float nu) const;
    float mie_phase(float nu) const;
    MiePhaseModel mie_phase_model() const { return mie_model_; }
    float mie_g() const { return mie_g_; }

private:
    std::size_t first_, count_;
    double bottom_radius_, top_radius_, thickness_, inv_table_step_;
    Spectrum4 solar_irradiance_, ground_albedo_;
    float sun_angular_radius_;
    MiePhaseModel mie_model_;
    float mie_g_;
    std::vector<MediumSample> table_;
    std::vector<ExtinctionEntry> extinction_;
    std::vector<double> breakpoint_radii_;
};

// Copies lanes [0, count) of v into out[0..count).
inline void store_channels(const Spectrum4& v, std::size_t count, float* out) {
    for (std::size_t c = 0; c < count; ++c) out[c] = v[int(c)];
}

}  // namespace welkin
