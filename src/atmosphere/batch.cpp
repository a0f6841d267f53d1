// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/batch.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/phase.hpp"
#include "welkin/base/error.hpp"

namespace welkin {
namespace {

Spectrum4 pack(const std::vector<double>& v, std::size_t first, std::size_t count) {
    Spectrum4 s(0.0f);
    for (int lane = 0; lane < 4; ++lane)
        s[lane] = float(v[first + std::min<std::size_t>(std::size_t(lane), count - 1)]);
    return s;
}

}  // namespace

AtmosphereBatch::AtmosphereBatch(const Atmosphere& atm, std::size_t first, std::size_t count)
    : first_(first),
      count_(count),
      bottom_radius_(atm.bottom_radius_m),
      top_radius_(atm.top_radius_m),
      thickness_(atm.top_radius_m - atm.bottom_radius_m),
      inv_table_step_(double(kTableSize - 1) /
                      ((atm.top_radius_m - atm.bottom_radius_m) * (atm.top_radius_m + atm.bottom_radius_m))),
      solar_irradiance_(pack(atm.solar_irradiance, first, count)),
      ground_albedo_(pack(atm.ground_albedo, first, count)),
      sun_angular_radius_(float(atm.sun_angular_radius_rad)),
      mie_model_(atm.mie_phase),
      mie_g_(float(atm.mie_g)),
      table_(kTableSize),
      extinction_(kTableSize) {
    if (count < 1 || count > 4 || first + count > atm.channels())
        throw InvalidArgument("channels", "a batch holds 1 to 4 of the atmosphere's channels");
    const Spectrum4 rayleigh = pack(atm.rayleigh_scattering, first, count);
    const Spectrum4 mie_s = pack(atm.mie_scattering, first, count);
    const Spectrum4 mie_t = pack(atm.mie_extinction, first, count);
    const Spectrum4 absorption = pack(atm.absorption_extinction, first, count);
    // Entries are independent: filled in parallel (the same values at any thread count).
    tbb::parallel_for(
        tbb::blocked_range<int>(0, kTableSize, 1024), [&](const tbb::blocked_range<int>& range) {
            for (int i = range.begin(); i != range.end(); ++i) {
                // r^2 - R^2 = s at entry i, so h = r - R = s / (r + R), without cancellation.
                const double s = double(i) / inv_table_step_;
                const double h = i + 1 == kTableSize
                                     ? thickness_
                                     : s / (std::sqrt(bottom_radius_ * bottom_radius_ + s) + bottom_radius_);
                const float rho_r = float(atm.rayleigh_density.density(h));
                const float rho_m = float(atm.mie_density.density(h));
                const float rho_a = float(atm.absorption_density.density(h));
                table_[std::size_t(i)] = {rayleigh * rho_r, mie_s * rho_m,
                                          rayleigh * rho_r + mie_t * rho_m + absorption * rho_a};
            }
        });
    for (const DensityProfile* profile : {&atm.rayleigh_density, &atm.mie_density, &atm.absorption_density})
        for (double h : profile->breakpoints_m())
            if (h > 0.0 && h < thickness_) breakpoint_radii_.push_back(bottom_radius_ + h);
    std::sort(breakpoint_radii_.begin(), breakpoint_radii_.end());
    breakpoint_radii_.erase(std::unique(breakpoint_radii_.begin(), breakpoint_radii_.end()),
                            breakpoint_radii_.end());
    for (int i = 0; i < kTableSize; ++i) {
        const Float4 a = to_float4(table_[std::size_t(i)].extinction);
        const Float4 b = i + 1 < kTableSize ? to_float4(table_[std::size_t(i) + 1].extinction) : a;
        extinction_[std::size_t(i)] = {a, b - a};
    }
}

std::vector<AtmosphereBatch> AtmosphereBatch::split(const Atmosphere& atm) {
    std::vector<AtmosphereBatch> batches;
    for (std::size_t first = 0; first < atm.channels(); first += 4)
        batches.emplace_back(atm, first, std::min<std::size_t>(4, atm.channels() - first));
    return batches;
}

float AtmosphereBatch::rayleigh_phase(float nu) const { return welkin::rayleigh_phase(nu); }
float AtmosphereBatch::mie_phase(float nu) const { return welkin::mie_phase(mie_model_, nu, mie_g_); }

}  // namespace welkin
