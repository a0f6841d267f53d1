// PLACEHOLDER until the analytic method lands: it refuses to run rather than return anything.
#include "welkin/analytic_sky.hpp"

#include <stdexcept>

namespace welkin {

AnalyticSky::AnalyticSky(const SkyOptions& options) : options_(options) {}

void AnalyticSky::radiance(const Atmosphere&, const Observer&, std::span<const glm::dvec3>,
                       std::span<float>, std::span<float>, Progress*) const {
    throw std::logic_error("the analytic method is not implemented yet");
}

}  // namespace welkin
