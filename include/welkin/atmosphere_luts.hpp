// The look-up tables that depend on the atmosphere alone (DESIGN.md, data flow): for each
// batch of four channels, the transmittance and the multiple-scattering LUTs. Built once
// per atmosphere; the per-view sky-view LUT (skyview_lut.hpp) and the ray-march method
// read them. Immutable after construction, so any number of threads may read it.
#pragma once

#include <memory>
#include <vector>

#include "welkin/multiscattering_lut.hpp"
#include "welkin/sky_method.hpp"

namespace welkin {

class AtmosphereLuts {
public:
    struct Batch {
        AtmosphereBatch medium;
        TransmittanceLut transmittance;
        MultiScatteringLut multiscattering;
    };

    AtmosphereLuts(const Atmosphere& atmosphere, const SkyOptions& options);

    const std::vector<std::unique_ptr<Batch>>& batches() const { return batches_; }
    std::size_t channels() const { return channels_; }

private:
    std::size_t channels_;
    std::vector<std::unique_ptr<Batch>> batches_;
};

}  // namespace welkin
