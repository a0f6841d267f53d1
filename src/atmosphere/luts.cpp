// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/luts.hpp"

#include "welkin/base/error.hpp"

namespace welkin {

void LutResolution::validate() const {
    require_in_range("transmittance_width", transmittance_width, 4, 4096);
    require_in_range("transmittance_height", transmittance_height, 4, 4096);
    require_in_range("multiscattering_size", multiscattering_size, 4, 1024);
}

AtmosphereLuts::AtmosphereLuts(const Atmosphere& atmosphere, const LutResolution& resolution)
    : channels_(atmosphere.channels()) {
    atmosphere.validate();
    resolution.validate();
    for (AtmosphereBatch& medium : AtmosphereBatch::split(atmosphere)) {
        TransmittanceLut t(medium, resolution.transmittance_width, resolution.transmittance_height);
        MultiScatteringLut ms(medium, t, resolution.multiscattering_size);
        batches_.push_back(std::make_unique<Batch>(Batch{std::move(medium), std::move(t), std::move(ms)}));
    }
}

}  // namespace welkin
