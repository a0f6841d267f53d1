// SPDX-License-Identifier: Apache-2.0
// What lights a cloud; see clouds/illumination.hpp.
#include "welkin/clouds/illumination.hpp"

#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"

namespace welkin {
namespace {

glm::dvec3 unit_sun(const glm::dvec3& s) {
    const double l = glm::length(s);
    if (!(l > 0.0) || !std::isfinite(l))
        throw InvalidArgument("sun_direction", "must be a finite non-zero vector");
    return s / l;
}

}  // namespace

ConstantIllumination::ConstantIllumination(const glm::dvec3& sun_direction, std::vector<float> sun_irradiance,
                                           std::vector<float> ambient_radiance)
    : s_(unit_sun(sun_direction)), sun_(std::move(sun_irradiance)), ambient_(std::move(ambient_radiance)) {
    if (sun_.empty() || sun_.size() != ambient_.size())
        throw InvalidArgument("ambient_radiance",
                              fmt::format("must have as many channels as sun_irradiance ({}), got {}",
                                          sun_.size(), ambient_.size()));
    for (std::size_t c = 0; c < sun_.size(); ++c) {
        require_in_range(fmt::format("sun_irradiance[{}]", c), sun_[c], 0.0, 1e9);
        require_in_range(fmt::format("ambient_radiance[{}]", c), ambient_[c], 0.0, 1e9);
    }
}

void ConstantIllumination::sun_irradiance(const glm::dvec3&, float* out) const {
    std::copy(sun_.begin(), sun_.end(), out);
}
void ConstantIllumination::ambient_radiance(const glm::dvec3&, float* out) const {
    std::copy(ambient_.begin(), ambient_.end(), out);
}

AtmosphereIllumination::AtmosphereIllumination(const Atmosphere& atmosphere, const Observer& observer,
                                               const LutResolution& resolution) {
    atmosphere.validate();
    resolution.validate();
    const Observer obs = observer.validated();
    s_ = obs.sun_direction;
    centre_ = {0.0, 0.0, -(atmosphere.bottom_radius_m + obs.altitude_m)};
    luts_ = std::make_shared<const AtmosphereLuts>(atmosphere, resolution);
}

glm::dvec3 AtmosphereIllumination::zenith(const glm::dvec3& p) const { return glm::normalize(p - centre_); }

void AtmosphereIllumination::sun_irradiance(const glm::dvec3& p, float* out) const {
    const glm::dvec3 q = p - centre_;
    const double r = glm::length(q);
    const double mu_s = clamp_cosine(glm::dot(q, s_) / r);
    for (const auto& b : luts_->batches()) {
        const Spectrum4 e = b->medium.solar_irradiance() * b->transmittance.to_sun(r, mu_s);
        store_channels(e, b->medium.channel_count(), out + b->medium.first_channel());
    }
}

void AtmosphereIllumination::ambient_radiance(const glm::dvec3& p, float* out) const {
    const glm::dvec3 q = p - centre_;
    const double r = glm::length(q);
    const double mu_s = clamp_cosine(glm::dot(q, s_) / r);
    for (const auto& b : luts_->batches()) {
        const Spectrum4 l = b->medium.solar_irradiance() * b->multiscattering.psi(r, mu_s);
        store_channels(glm::max(l, Spectrum4(0.0f)), b->medium.channel_count(),
                       out + b->medium.first_channel());
    }
}

}  // namespace welkin
