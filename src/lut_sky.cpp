// PLACEHOLDER until the lut method lands: it refuses to run rather than return anything.
#include "welkin/lut_sky.hpp"

#include <stdexcept>

namespace welkin {

LutSky::LutSky(const SkyOptions& options) : options_(options) {}

void LutSky::radiance(const Atmosphere&, const Observer&, std::span<const glm::dvec3>,
                       std::span<float>, std::span<float>, Progress*) const {
    throw std::logic_error("the lut method is not implemented yet");
}

}  // namespace welkin
