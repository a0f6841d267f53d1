// PLACEHOLDER until the raymarch method lands: it refuses to run rather than return anything.
#include "welkin/raymarch_sky.hpp"

#include <stdexcept>

namespace welkin {

RaymarchSky::RaymarchSky(const SkyOptions& options) : options_(options) {}

void RaymarchSky::radiance(const Atmosphere&, const Observer&, std::span<const glm::dvec3>,
                       std::span<float>, std::span<float>, Progress*) const {
    throw std::logic_error("the raymarch method is not implemented yet");
}

}  // namespace welkin
