// SPDX-License-Identifier: Apache-2.0
// The look-up tables that depend on the atmosphere alone (docs/design.md#data-flow): for each
// batch of four channels, the transmittance and the multiple-scattering LUTs. Built once
// per atmosphere; the per-view sky-view LUT (skyview_lut.hpp) and the ray-march method
// read them. Immutable after construction, so any number of threads may read it.
#pragma once

#include <memory>
#include <vector>

#include "welkin/atmosphere/multiscattering_lut.hpp"

namespace welkin {

// The sizes of the atmosphere's LUTs (Hillaire 2020's defaults): transmittance as
// width x height over (view zenith, altitude), multiple scattering as size x size over
// (sun zenith, altitude).
struct LutResolution {
    int transmittance_width = 256, transmittance_height = 64;
    int multiscattering_size = 32;

    // Throws InvalidArgument naming the size and its range (4-4096, 4-4096, 4-1024).
    void validate() const;
    bool operator==(const LutResolution&) const = default;
};

class AtmosphereLuts {
public:
    struct Batch {
        AtmosphereBatch medium;
        TransmittanceLut transmittance;
        MultiScatteringLut multiscattering;
    };

    AtmosphereLuts(const Atmosphere& atmosphere, const LutResolution& resolution);

    const std::vector<std::unique_ptr<Batch>>& batches() const { return batches_; }
    std::size_t channels() const { return channels_; }

private:
    std::size_t channels_;
    std::vector<std::unique_ptr<Batch>> batches_;
};

}  // namespace welkin
