// SPDX-License-Identifier: Apache-2.0
// The "raymarch" sky method; see sky/method.hpp for the ladder and src/sky/raymarch.cpp for the
// derivation.
#pragma once

#include "welkin/sky/method.hpp"

namespace welkin {

class RaymarchSky final : public SkyMethod {
public:
    explicit RaymarchSky(const SkyOptions& options = {});
    std::string name() const override { return "raymarch"; }
    void radiance(const Atmosphere& atmosphere, const Observer& observer,
                  std::span<const glm::dvec3> directions, std::span<float> out,
                  std::span<float> standard_error = {}, Progress* progress = nullptr) const override;

private:
    SkyOptions options_;
};

}  // namespace welkin
