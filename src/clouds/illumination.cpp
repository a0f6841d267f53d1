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
    : ConstantIllumination(sun_direction, std::move(sun_irradiance), ambient_radiance, ambient_radiance) {}

ConstantIllumination::ConstantIllumination(const glm::dvec3& sun_direction, std::vector<float> sun_irradiance,
                                           std::vector<float> ambient_radiance,
                                           std::vector<float> ground_radiance)
    : s_(unit_sun(sun_direction)),
      sun_(std::move(sun_irradiance)),
      above_(std::move(ambient_radiance)),
      below_(std::move(ground_radiance)) {
    for (const auto& [name, v] :
         {std::pair<const char*, const std::vector<float>*>{"ambient_radiance", &above_},
          {"ground_radiance", &below_}})
        if (sun_.empty() || sun_.size() != v->size())
            throw InvalidArgument(
                name, fmt::format("must have as many channels as sun_irradiance ({}), got {}", sun_.size(),
                                  v->size()));
    for (std::size_t c = 0; c < sun_.size(); ++c) {
        require_in_range(fmt::format("sun_irradiance[{}]", c), sun_[c], 0.0, 1e9);
        require_in_range(fmt::format("ambient_radiance[{}]", c), above_[c], 0.0, 1e9);
        require_in_range(fmt::format("ground_radiance[{}]", c), below_[c], 0.0, 1e9);
    }
}

void ConstantIllumination::sun_irradiance(const glm::dvec3&, float* out) const {
    std::copy(sun_.begin(), sun_.end(), out);
}
void ConstantIllumination::sky_radiance(const glm::dvec3&, float* above, float* below) const {
    std::copy(above_.begin(), above_.end(), above);
    std::copy(below_.begin(), below_.end(), below);
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

void AtmosphereIllumination::sky_radiance(const glm::dvec3& p, float* above, float* below) const {
    const glm::dvec3 q = p - centre_;
    const double r = glm::length(q);
    const double mu_s = clamp_cosine(glm::dot(q, s_) / r);
    for (const auto& b : luts_->batches()) {
        Spectrum4 up, down;
        b->multiscattering.hemispheres(r, mu_s, up, down);
        const Spectrum4 e = b->medium.solar_irradiance();
        const int n = b->medium.channel_count(), first = b->medium.first_channel();
        store_channels(glm::max(e * up, Spectrum4(0.0f)), n, above + first);
        store_channels(glm::max(e * down, Spectrum4(0.0f)), n, below + first);
    }
}

}  // namespace welkin
