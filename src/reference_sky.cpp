// PLACEHOLDER until the reference method lands: it refuses to run rather than return anything.
#include "welkin/reference_sky.hpp"

#include <stdexcept>

namespace welkin {

ReferenceSky::ReferenceSky(const SkyOptions& options) : options_(options) {}

void ReferenceSky::radiance(const Atmosphere&, const Observer&, std::span<const glm::dvec3>,
                       std::span<float>, std::span<float>, Progress*) const {
    throw std::logic_error("the reference method is not implemented yet");
}

}  // namespace welkin
