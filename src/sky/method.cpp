// SPDX-License-Identifier: Apache-2.0
#include "welkin/sky/method.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"
#include "welkin/sky/analytic.hpp"
#include "welkin/sky/auto.hpp"
#include "welkin/sky/lut.hpp"
#include "welkin/sky/raymarch.hpp"
#include "welkin/sky/reference.hpp"

namespace welkin {

void SkyOptions::validate() const {
    luts().validate();
    require_in_range("skyview_width", skyview_width, 4, 8192);
    require_in_range("skyview_height", skyview_height, 4, 8192);
    require_in_range("raymarch_steps", raymarch_steps, 1, 100000);
    require_in_range("raymarch_sun_steps", raymarch_sun_steps, 1, 100000);
    require_in_range("reference_paths", reference_paths, 1, 1 << 26);
    require_in_range("tolerance", tolerance, kMinTolerance, kMaxTolerance, "(relative luminance error)");
}

Observer validate_deterministic_call(const Atmosphere& atmosphere, const Observer& observer,
                                     std::span<const glm::dvec3> directions, std::span<float> out,
                                     std::span<float> standard_error) {
    atmosphere.validate();
    const Observer validated = observer.validated();
    validate_directions(directions);
    if (out.size() != directions.size() * atmosphere.channels())
        throw InvalidArgument("out", "must hold directions x channels values");
    if (!standard_error.empty() && standard_error.size() != out.size())
        throw InvalidArgument("standard_error", "must be empty or hold directions x channels values");
    std::fill(standard_error.begin(), standard_error.end(), 0.0f);
    return validated;
}

std::vector<std::string> sky_method_names() { return {"analytic", "lut", "raymarch", "reference", "auto"}; }

std::unique_ptr<SkyMethod> make_sky_method(const std::string& name, const SkyOptions& options) {
    options.validate();
    if (name == "analytic") return std::make_unique<AnalyticSky>(options);
    if (name == "lut") return std::make_unique<LutSky>(options);
    if (name == "raymarch") return std::make_unique<RaymarchSky>(options);
    if (name == "reference") return std::make_unique<ReferenceSky>(options);
    if (name == "auto") return std::make_unique<AutoSky>(options);
    throw InvalidArgument("method", fmt::format("unknown method '{}'; choose one of: {}", name,
                                                fmt::join(sky_method_names(), ", ")));
}

SkyResult sky_radiance(const SkyMethod& method, const Atmosphere& atmosphere, const Observer& observer,
                       std::span<const glm::dvec3> directions, Progress* progress) {
    SkyResult r;
    r.channels = atmosphere.channels();
    r.radiance.resize(directions.size() * r.channels);
    r.standard_error.resize(directions.size() * r.channels);
    method.radiance(atmosphere, observer, directions, r.radiance, r.standard_error, progress);
    return r;
}

}  // namespace welkin
