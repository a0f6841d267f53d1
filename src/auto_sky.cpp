// The "auto" sky method; the rules are in include/welkin/auto_sky.hpp, the numbers in the
// generated src/auto_sky_table.cpp (bench/chart.py).
#include "welkin/auto_sky.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "welkin/auto_sky_table.hpp"
#include "welkin/error.hpp"
#include "welkin/math.hpp"

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
                Atmosphere::preset(t.presets[p], atmosphere.wavelengths_nm).to_json_string() ==
                    own)
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

AutoChoice choose_sky_method(const Atmosphere& atmosphere, const Observer& observer,
                             std::size_t directions, double tolerance, const SkyOptions& options) {
    return choose_sky_method(atmosphere, observer, directions, tolerance, options,
                             auto_table::table());
}

AutoChoice choose_sky_method(const Atmosphere& atmosphere, const Observer& observer,
                             std::size_t directions, double tolerance, const SkyOptions& options,
                             const auto_table::Table& t) {
    require_in_range("tolerance", tolerance, kMinTolerance, kMaxTolerance,
                     "(relative luminance error)");
    atmosphere.validate();
    const Observer obs = observer.validated();

    // The scene's place on the chart's grid. Sun elevation: asin of the sun direction's
    // vertical component (the observer's zenith is +Z).
    const double sun_elevation_deg =
        std::asin(std::clamp(obs.sun_direction.z, -1.0, 1.0)) * 180.0 / kPi;
    const auto [a0, a1] = bracket(t.altitudes_m, obs.altitude_m);
    const auto [s0, s1] = bracket(t.sun_elevations_deg, sun_elevation_deg);
    const std::vector<std::size_t> presets = presets_for(atmosphere, t);
    // Three wavelengths are judged by the 3-wavelength rows; more by the spectral rows.
    const bool spectral = atmosphere.channels() > 3;

    const auto_table::Setting* best = nullptr;
    double best_error = auto_table::kInf, best_seconds = auto_table::kInf;
    bool best_meets = false;
    for (std::size_t k = 0; k < t.settings.size(); ++k) {
        const auto_table::Setting& s = t.settings[k];
        if (s.spectral != spectral) continue;
        double error = 0.0;
        for (std::size_t p : presets)
            for (std::size_t a : {a0, a1})
                for (std::size_t e : {s0, s1}) error = std::max(error, t.p95_at(p, k, a, e));
        if (!std::isfinite(error)) continue;  // known to fail here
        const double seconds = s.fixed_seconds + s.seconds_per_direction * double(directions);
        const bool meets = error <= tolerance;
        // Meeting the tolerance beats not; among those that meet it the cheapest wins,
        // among those that do not the most accurate (then the cheapest).
        bool better;
        if (!best) better = true;
        else if (meets != best_meets) better = meets;
        else if (meets) better = seconds < best_seconds;
        else better = error < best_error || (error == best_error && seconds < best_seconds);
        if (better) {
            best = &s;
            best_error = error;
            best_seconds = seconds;
            best_meets = meets;
        }
    }
    // The analytic method is finite everywhere the stability sweep looks; the table marks
    // it infinite only if a chart run saw otherwise.
    if (!best)
        throw std::runtime_error(fmt::format("auto: every charted method gave non-finite values near "
                                "altitude {} m, sun elevation {} deg; regenerate the table "
                                "(bench/chart.py)",
                                obs.altitude_m, sun_elevation_deg));

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
