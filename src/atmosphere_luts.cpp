#include "welkin/atmosphere_luts.hpp"

namespace welkin {

AtmosphereLuts::AtmosphereLuts(const Atmosphere& atmosphere, const SkyOptions& options)
    : channels_(atmosphere.channels()) {
    atmosphere.validate();
    options.validate();
    for (AtmosphereBatch& medium : AtmosphereBatch::split(atmosphere)) {
        TransmittanceLut t(medium, options.transmittance_width, options.transmittance_height);
        MultiScatteringLut ms(medium, t, options.multiscattering_size);
        batches_.push_back(std::make_unique<Batch>(Batch{std::move(medium), std::move(t), std::move(ms)}));
    }
}

}  // namespace welkin
