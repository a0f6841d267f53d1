// SPDX-License-Identifier: Apache-2.0
// The "analytic" sky method; see sky/method.hpp for the ladder and src/sky/analytic.cpp for the
// derivation.
#pragma once

#include "welkin/sky/method.hpp"

namespace welkin {

class AnalyticSky final : public SkyMethod {
public:
    explicit AnalyticSky(const SkyOptions& options = {});
    std::string name() const override { return "analytic"; }
    void radiance(const Atmosphere& atmosphere, const Observer& observer,
                  std::span<const glm::dvec3> directions, std::span<float> out,
                  std::span<float> standard_error = {}, Progress* progress = nullptr) const override;

private:
    SkyOptions options_;
};

}  // namespace welkin
