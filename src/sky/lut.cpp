// SPDX-License-Identifier: Apache-2.0
// The "lut" method: Hillaire 2020's pipeline. Per atmosphere, the transmittance and
// multiple-scattering LUTs (atmosphere/luts.hpp), kept between calls by a cache
// (lut_cache.hpp); per observer and sun, the sky-view LUT (skyview_lut.hpp); per
// direction, one bilinear lookup.
//
// Known failure and its fallback: the sky-view LUT describes the sky around a point inside
// the atmosphere. For an observer above the top, this method hands the directions to the
// ray-march (with the same options), which is right there, and slower.
#include "welkin/sky/lut.hpp"

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/lut_cache.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/skyview_lut.hpp"
#include "welkin/base/error.hpp"
#include "welkin/sky/raymarch.hpp"

namespace welkin {

LutSky::LutSky(const SkyOptions& options, AtmosphereLutCache* cache) : options_(options), cache_(cache) {
    options_.validate();
}

AtmosphereLutCache* LutSky::default_cache() { return &AtmosphereLutCache::shared(); }

void LutSky::radiance(const Atmosphere& atm, const Observer& observer_in,
                      std::span<const glm::dvec3> directions_in, std::span<float> out,
                      std::span<float> standard_error, Progress* progress) const {
    const Observer observer =
        validate_deterministic_call(atm, observer_in, directions_in, out, standard_error);
    const std::span<const glm::dvec3> directions = directions_in;
    const std::size_t C = atm.channels();
    const double r = atm.bottom_radius_m + observer.altitude_m;
    if (r >= atm.top_radius_m) {
        RaymarchSky(options_).radiance(atm, observer, directions, out, {}, progress);
        return;
    }
    const std::shared_ptr<const AtmosphereLuts> luts =
        cache_ ? cache_->get(atm, options_.luts())
               : std::make_shared<const AtmosphereLuts>(atm, options_.luts());
    ProgressTracker tracker(progress, directions.size() * luts->batches().size());
    for (const auto& b : luts->batches()) {
        const SkyViewLut sky(b->medium, b->transmittance, b->multiscattering, r, observer.sun_direction.z,
                             options_.skyview_width, options_.skyview_height);
        const std::size_t first = b->medium.first_channel(), count = b->medium.channel_count();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, directions.size(), 4096),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              sky.radiance(directions.subspan(range.begin(), range.size()),
                                           observer.sun_direction, count, &out[range.begin() * C + first], C);
                              tracker.advance(range.size());
                          });
    }
    tracker.finish();
}

}  // namespace welkin
