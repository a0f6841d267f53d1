// SPDX-License-Identifier: Apache-2.0
// The "auto" sky method; the rules are in include/welkin/sky/auto.hpp, the numbers in the
// generated src/sky/auto_table.cpp (bench/chart.py).
#include "welkin/sky/auto.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/sky/auto_table.hpp"

namespace welkin {
namespace {

// Indices of the grid values around x: lo = the last value <= x, hi = the first >= x,
// both the edge when x lies outside the grid.
std::pair<std::size_t, std::size_t> bracket(std::span<const double> grid, double x) {
    const std::size_t n = grid.size();
    if (x <= grid[0]) return {0, 0};
    if (x >= grid[n - 1]) return {n - 1, n - 1};
    const std::size_t hi = std::size_t(std::lower_bound(grid.begin(), grid.end(), x) - grid.begin());
    const std::size_t lo = grid[hi] == x ? hi : hi - 1;
    return {lo, hi};
}

// The charted presets this atmosphere is judged by: the one it equals exactly (at its own
// wavelengths), else all of them.
std::vector<std::size_t> presets_for(const Atmosphere& atmosphere, const auto_table::Table& t) {
    const std::string own = atmosphere.to_json_string();
    for (std::size_t p = 0; p < t.presets.size(); ++p) {
        if (atmosphere.name != t.presets[p]) continue;
        try {
            // The preset at its own three wavelengths, or resampled at the atmosphere's.
            if (Atmosphere::preset(t.presets[p]).to_json_string() == own ||
                Atmosphere::preset(t.presets[p], atmosphere.wavelengths_nm).to_json_string() == own)
                return {p};
        } catch (const InvalidArgument&) {
            // Wavelengths the preset cannot be resampled at: not this preset.
        }
    }
    std::vector<std::size_t> all(t.presets.size());
    for (std::size_t p = 0; p < all.size(); ++p) all[p] = p;
    return all;
}

std::string setting_label(const auto_table::Setting& s) {
    const std::string mode = s.spectral ? " spectral" : "";
    if (std::string(s.method) == "lut")
        return fmt::format("lut {}x{}/{}/{}x{}{}", s.transmittance_width, s.transmittance_height,
                           s.multiscattering_size, s.skyview_width, s.skyview_height, mode);
    if (std::string(s.method) == "raymarch")
        return fmt::format("raymarch {}/{}{}", s.raymarch_steps, s.raymarch_sun_steps, mode);
    return std::string(s.method) + mode;
}

}  // namespace

AutoChoice choose_sky_method(const Atmosphere& atmosphere, const Observer& observer, std::size_t directions,
                             double tolerance, const SkyOptions& options) {
    return choose_sky_method(atmosphere, observer, directions, tolerance, options, auto_table::table());
}

AutoChoice choose_sky_method(const Atmosphere& atmosphere, const Observer& observer, std::size_t directions,
                             double tolerance, const SkyOptions& options, const auto_table::Table& t) {
    require_in_range("tolerance", tolerance, kMinTolerance, kMaxTolerance, "(relative luminance error)");
    atmosphere.validate();
    const Observer obs = observer.validated();

    // The scene's place on the chart's grid. Sun elevation: asin of the sun direction's
    // vertical component (the observer's zenith is +Z).
    const double sun_elevation_deg = std::asin(std::clamp(obs.sun_direction.z, -1.0, 1.0)) * 180.0 / kPi;
    const auto [a0, a1] = bracket(t.altitudes_m, obs.altitude_m);
    const auto [s0, s1] = bracket(t.sun_elevations_deg, sun_elevation_deg);
    const std::vector<std::size_t> presets = presets_for(atmosphere, t);
    // Up to four wavelengths (the default four, or three: one SIMD batch of the fast
    // methods, atmosphere/batch.hpp) are judged by the chart's default rows; more by its
    // spectral rows.
    const bool spectral = atmosphere.channels() > 4;

    // The measured error of every setting of the right kind at this scene: the worst over
    // the presets and the grid corners around it (infinite where it failed: never chosen).
    struct Candidate {
        const auto_table::Setting* setting;
        double error, seconds;
    };
    std::vector<Candidate> candidates;
    for (std::size_t k = 0; k < t.settings.size(); ++k) {
        const auto_table::Setting& s = t.settings[k];
        if (s.spectral != spectral) continue;
        double error = 0.0;
        for (std::size_t p : presets)
            for (std::size_t a : {a0, a1})
                for (std::size_t e : {s0, s1}) error = std::max(error, t.p95_at(p, k, a, e));
        if (!std::isfinite(error)) continue;  // known to fail here
        candidates.push_back({&s, error, s.fixed_seconds + s.seconds_per_direction * double(directions)});
    }
    // The analytic method is finite everywhere the stability sweep looks; the table marks
    // it infinite only if a chart run saw otherwise.
    if (candidates.empty())
        throw std::runtime_error(
            fmt::format("auto: every charted method gave non-finite values near "
                        "altitude {} m, sun elevation {} deg; regenerate the table "
                        "(bench/chart.py)",
                        obs.altitude_m, sun_elevation_deg));

    // The cheapest that meets the tolerance. If none does, the cheapest of those whose
    // error the chart cannot tell from the smallest: within the reference's own noise
    // there (its p95 relative standard error, worst corner), so that a setting 0.2 % more
    // accurate on paper but a thousand times slower is not picked.
    double min_error = auto_table::kInf, noise = 0.0;
    for (const Candidate& c : candidates) min_error = std::min(min_error, c.error);
    for (std::size_t p : presets)
        for (std::size_t a : {a0, a1})
            for (std::size_t e : {s0, s1})
                noise = std::max(
                    noise,
                    t.reference_noise[(p * t.altitudes_m.size() + a) * t.sun_elevations_deg.size() + e]);
    const bool meets = min_error <= tolerance;
    const double accept = meets ? tolerance : min_error + noise;
    const Candidate* chosen = nullptr;
    for (const Candidate& c : candidates)
        if (c.error <= accept && (!chosen || c.seconds < chosen->seconds ||
                                  (c.seconds == chosen->seconds && c.error < chosen->error)))
            chosen = &c;
    const auto_table::Setting* best = chosen->setting;
    const double best_error = chosen->error, best_seconds = chosen->seconds;
    const bool best_meets = meets;

    AutoChoice c;
    c.method = best->method;
    c.options = options;
    c.options.transmittance_width = best->transmittance_width;
    c.options.transmittance_height = best->transmittance_height;
    c.options.multiscattering_size = best->multiscattering_size;
    c.options.skyview_width = best->skyview_width;
    c.options.skyview_height = best->skyview_height;
    c.options.raymarch_steps = best->raymarch_steps;
    c.options.raymarch_sun_steps = best->raymarch_sun_steps;
    c.setting = setting_label(*best);
    c.predicted_error = best_error;
    c.predicted_seconds = best_seconds;
    c.meets_tolerance = best_meets;
    return c;
}

AutoSky::AutoSky(const SkyOptions& options) : options_(options) { options_.validate(); }

void AutoSky::radiance(const Atmosphere& atmosphere, const Observer& observer,
                       std::span<const glm::dvec3> directions, std::span<float> out,
                       std::span<float> standard_error, Progress* progress) const {
    const AutoChoice c =
        choose_sky_method(atmosphere, observer, directions.size(), options_.tolerance, options_);
    make_sky_method(c.method, c.options)
        ->radiance(atmosphere, observer, directions, out, standard_error, progress);
}

}  // namespace welkin
