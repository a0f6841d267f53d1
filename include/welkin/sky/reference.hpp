// SPDX-License-Identifier: Apache-2.0
// The "reference" sky method: Monte-Carlo path tracing through the atmosphere, all
// scattering orders, ground reflection, Earth shadow, seeded and thread-count independent.
// See sky/method.hpp for the ladder and src/sky/reference.cpp for the derivation.
//
// Thread safety: radiance() is const and may run concurrently; it parallelises itself
// with TBB (results do not depend on the thread count).
#pragma once

#include "welkin/sky/method.hpp"

namespace welkin {

class ReferenceSky final : public SkyMethod {
public:
    // options.reference_paths: Monte-Carlo paths per direction; every path carries all the
    // atmosphere's wavelengths, so it is also the number of paths per wavelength.
    // options.seed: the seed. max_scattering_order: 0 for all orders (the method's
    // definition); n > 0 keeps only light scattered at most n times, counting ground
    // reflections as scattering events (tests use it to check single scattering against
    // closed forms and to watch the orders converge).
    explicit ReferenceSky(const SkyOptions& options = {}, int max_scattering_order = 0);
    std::string name() const override { return "reference"; }
    void radiance(const Atmosphere& atmosphere, const Observer& observer,
                  std::span<const glm::dvec3> directions, std::span<float> out,
                  std::span<float> standard_error = {}, Progress* progress = nullptr) const override;

    // Batches the paths of one direction are split into; the standard error is the spread
    // of the batch means (see the derivation).
    static constexpr int kBatches = 32;

private:
    SkyOptions options_;
    int max_order_;
};

}  // namespace welkin
