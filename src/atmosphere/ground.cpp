// SPDX-License-Identifier: Apache-2.0
// The lit ground below the horizon; see ground.hpp.
#include "welkin/atmosphere/ground.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <list>
#include <mutex>
#include <utility>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/lut_cache.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/atmosphere/skyview_lut.hpp"
#include "welkin/atmosphere/sun.hpp"
#include "welkin/base/math.hpp"

namespace welkin {
namespace {

// 8-point Gauss-Legendre on [0, 1] (Abramowitz & Stegun 25.4.30, mapped).
constexpr std::array<double, 4> kNodes = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                          0.9602898564975363};
constexpr std::array<double, 4> kWeights = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                            0.1012285362903763};
constexpr int kAzimuths = 16;  // over [0, pi], mirrored
// A small sky-view LUT per tabulated sun suffices for an integral over the hemisphere.
constexpr int kSkyViewWidth = 48, kSkyViewHeight = 32;

double mu_s_of(int i) {
    return GroundIllumination::kMinMuS +
           (1.0 - GroundIllumination::kMinMuS) * i / (GroundIllumination::kTableSize - 1);
}

}  // namespace

std::vector<double> transmittance_along(const Atmosphere& atm, double r, double mu, double length_m) {
    if (r > atm.top_radius_m) {
        // From space: only the part of the segment inside the atmosphere attenuates.
        const double entry = distance_to_atmosphere_entry(r, mu, atm.top_radius_m);
        if (entry < 0.0 || entry >= length_m) return std::vector<double>(atm.channels(), 1.0);
        const double r_entry = std::min(radius_at(r, mu, entry), atm.top_radius_m);
        return transmittance_along(atm, r_entry, mu_at(r, mu, entry, r_entry), length_m - entry);
    }
    const ColumnDensity column = column_density(atm, r, mu, length_m);
    std::vector<double> t(atm.channels());
    for (std::size_t c = 0; c < t.size(); ++c) t[c] = std::exp(-optical_depth(atm, c, column));
    return t;
}

GroundIllumination::GroundIllumination(const Atmosphere& atm) : channels_(atm.channels()) {
    atm.validate();
    const std::size_t nc = channels_;
    sun_.assign(std::size_t(kTableSize) * nc, 0.0);
    sky_.assign(std::size_t(kTableSize) * nc, 0.0);
    const std::shared_ptr<const AtmosphereLuts> luts = AtmosphereLutCache::shared().get(atm, LutResolution{});
    const double R = atm.bottom_radius_m;
    for (int i = 0; i < kTableSize; ++i) {
        const double mu_s = mu_s_of(i);
        const Observer at_ground{0.0, {safe_sqrt(1.0 - mu_s * mu_s), 0.0, mu_s}};
        const SunRadiometry sun = sun_radiometry(atm, at_ground);
        for (std::size_t c = 0; c < nc; ++c)
            sun_[std::size_t(i) * nc + c] = sun.direct_irradiance[c] * std::max(mu_s, 0.0);
        for (const auto& b : luts->batches()) {
            const SkyViewLut view(b->medium, b->transmittance, b->multiscattering, R, mu_s, kSkyViewWidth,
                                  kSkyViewHeight);
            Spectrum4 e(0.0f);
            for (std::size_t k = 0; k < kNodes.size(); ++k)
                for (double mu : {0.5 * (1.0 - kNodes[k]), 0.5 * (1.0 + kNodes[k])})
                    for (int a = 0; a < kAzimuths; ++a) {
                        const double phi = kPi * (a + 0.5) / kAzimuths;
                        // dw = dmu dphi; both halves of the azimuth circle: factor 2.
                        const double w = 0.5 * kWeights[k] * mu * 2.0 * kPi / kAzimuths;
                        e += float(w) * view.radiance(mu, std::cos(phi));
                    }
            for (std::size_t c = 0; c < b->medium.channel_count(); ++c)
                sky_[std::size_t(i) * nc + b->medium.first_channel() + c] = double(e[int(c)]);
        }
    }
}

std::shared_ptr<const GroundIllumination> GroundIllumination::shared(const Atmosphere& atm) {
    constexpr std::size_t kCapacity = 2;
    static std::mutex mutex;
    static std::list<std::pair<Atmosphere, std::shared_ptr<const GroundIllumination>>>
        entries;  // recent first
    {
        const std::lock_guard<std::mutex> lock(mutex);
        for (auto it = entries.begin(); it != entries.end(); ++it)
            if (it->first == atm) {
                entries.splice(entries.begin(), entries, it);
                return entries.front().second;
            }
    }
    auto built = std::make_shared<const GroundIllumination>(atm);  // may throw: nothing cached
    const std::lock_guard<std::mutex> lock(mutex);
    entries.emplace_front(atm, built);
    if (entries.size() > kCapacity) entries.pop_back();
    return built;
}

GroundIllumination::Entry GroundIllumination::entry(double mu_s) const {
    const double x = (std::clamp(mu_s, kMinMuS, 1.0) - kMinMuS) / (1.0 - kMinMuS) * (kTableSize - 1);
    const int i = std::min(int(x), kTableSize - 2);
    return {std::size_t(i) * channels_, x - i};
}

void GroundIllumination::lookup(const std::vector<double>& table, double mu_s, std::span<double> out) const {
    const auto [a, f] = entry(mu_s);
    for (std::size_t c = 0; c < channels_; ++c)
        out[c] = table[a + c] * (1.0 - f) + table[a + channels_ + c] * f;
}

void GroundIllumination::sun_irradiance(double mu_s, std::span<double> out) const { lookup(sun_, mu_s, out); }
void GroundIllumination::sky_irradiance(double mu_s, std::span<double> out) const { lookup(sky_, mu_s, out); }
void GroundIllumination::irradiance(double mu_s, std::span<double> out) const {
    // Both tables at once: called per ground pixel, so no temporary.
    const auto [a, f] = entry(mu_s);
    const std::size_t b = a + channels_;
    for (std::size_t c = 0; c < channels_; ++c)
        out[c] = (sun_[a + c] + sky_[a + c]) * (1.0 - f) + (sun_[b + c] + sky_[b + c]) * f;
}

}  // namespace welkin
