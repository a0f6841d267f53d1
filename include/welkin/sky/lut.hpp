// SPDX-License-Identifier: Apache-2.0
// The "lut" sky method; see sky/method.hpp for the ladder and src/sky/lut.cpp for the
// derivation.
#pragma once

#include "welkin/sky/method.hpp"

namespace welkin {

class AtmosphereLutCache;

class LutSky final : public SkyMethod {
public:
    // `cache` keeps the atmosphere's LUTs between calls (lut_cache.hpp), so that a call
    // with the same atmosphere and LUT sizes builds only the sky-view LUT; by default the
    // process-wide one. nullptr builds every LUT in every call. A cache passed here must
    // outlive the LutSky.
    explicit LutSky(const SkyOptions& options = {}, AtmosphereLutCache* cache = default_cache());
    std::string name() const override { return "lut"; }
    void radiance(const Atmosphere& atmosphere, const Observer& observer,
                  std::span<const glm::dvec3> directions, std::span<float> out,
                  std::span<float> standard_error = {}, Progress* progress = nullptr) const override;

    static AtmosphereLutCache* default_cache();

private:
    SkyOptions options_;
    AtmosphereLutCache* cache_;
};

}  // namespace welkin
