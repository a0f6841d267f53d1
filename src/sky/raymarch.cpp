// SPDX-License-Identifier: Apache-2.0
// The "raymarch" method: for every direction, the single-scattering integral of
// inscattering.hpp with `raymarch_steps` samples along the view ray and, at each of them,
// a nested march of `raymarch_sun_steps` samples towards the sun for its transmittance
// (no transmittance LUT on the single-scattering path), plus Hillaire 2020's
// multiple-scattering term from the multiple-scattering LUT. Observers above the
// atmosphere are handled by moving to the ray's entry point.
#include "welkin/sky/raymarch.hpp"

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/inscattering.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/view_geometry.hpp"
#include "welkin/base/error.hpp"

namespace welkin {

RaymarchSky::RaymarchSky(const SkyOptions& options) : options_(options) { options_.validate(); }

void RaymarchSky::radiance(const Atmosphere& atm, const Observer& observer_in,
                           std::span<const glm::dvec3> directions_in, std::span<float> out,
                           std::span<float> standard_error, Progress* progress) const {
    const Observer observer =
        validate_deterministic_call(atm, observer_in, directions_in, out, standard_error);
    const std::span<const glm::dvec3> directions = directions_in;
    const std::size_t C = atm.channels();
    const double r = atm.bottom_radius_m + observer.altitude_m;
    const AtmosphereLuts luts(atm, options_.luts());
    ProgressTracker tracker(progress, directions.size() * luts.batches().size());
    for (const auto& b : luts.batches()) {
        const AtmosphereBatch& medium = b->medium;
        const double R = medium.bottom_radius(), top = medium.top_radius();
        const double angular_radius = atm.sun_angular_radius_rad;
        const GradedQuadrature sun_quadrature(options_.raymarch_sun_steps);
        const auto sun_t = [&](const RaySamples::Step& st, double mu_s_t) {
            const double r_t = st.r;
            const double fraction = sun_visible_fraction(R, r_t, mu_s_t, angular_radius);
            if (fraction <= 0.0) return Spectrum4(0.0f);
            const Spectrum4 tau =
                sun_quadrature.optical_depth(medium, r_t, mu_s_t, distance_to_top(r_t, mu_s_t, top));
            return glm::exp(-tau) * float(fraction);
        };
        const std::size_t first = medium.first_channel(), count = medium.channel_count();
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, directions.size(), 64),
            [&](const tbb::blocked_range<std::size_t>& range) {
                RaySamples ray;
                for (std::size_t i = range.begin(); i != range.end(); ++i) {
                    const ViewGeometry g = view_geometry(directions[i], observer.sun_direction);
                    prepare_ray(medium, r, g.mu, options_.raymarch_steps, ray, nullptr, &b->multiscattering);
                    store_channels(inscatter(medium, &b->multiscattering, ray, g.mu_s, g.nu, sun_t), count,
                                   &out[i * C + first]);
                }
                tracker.advance(range.size());
            });
    }
    tracker.finish();
}

}  // namespace welkin
