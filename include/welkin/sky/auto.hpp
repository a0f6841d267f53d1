// SPDX-License-Identifier: Apache-2.0
// The "auto" sky method: model no more than the scene needs.
//
// Given a tolerance on the relative luminance error, auto picks, per scene (observer
// altitude, sun elevation, number of directions, atmosphere), the cheapest charted method
// and setting whose measured error meets it, then runs that method. The measurements are
// the chart's (bench/chart.py -> sky/auto_table.hpp): the 95th percentile over the whole
// sphere of |Y - Y_ref| / Y_ref, Y the CIE luminance, against the spectral reference.
//
// How a scene between the chart's grid points is judged: by the worst of the grid
// corners around it (altitude and sun elevation each bracketed; outside the charted range
// the nearest edge), and, for an atmosphere that is not exactly one of the charted
// presets, by the worst over the presets. A method that gave a non-finite value at a
// corner is never chosen there. The cost of a setting on N directions is its measured
// fixed cost plus N times its per-direction cost, so a handful of directions may go to
// raymarch (no LUT builds) while an HDRI goes to lut.
//
// When no charted setting meets the tolerance (deep twilight, haze, tolerances below what
// the fast methods reach) auto falls back to the cheapest setting whose measured error
// there is within the reference's own noise of the smallest, and says so
// (AutoChoice::meets_tolerance = false). It never picks the reference:
// at the chart's settings a 2048 x 1024 reference sky takes hours, and a host should ask
// for it by name.
//
// Thread safety: choose_sky_method is a pure function; AutoSky::radiance is const.
#pragma once

#include <cstddef>
#include <string>

#include "welkin/sky/auto_table.hpp"
#include "welkin/sky/method.hpp"

namespace welkin {

struct AutoChoice {
    std::string method;            // the method to run: "analytic" | "lut" | "raymarch"
    SkyOptions options;            // the caller's options with this setting's sizes / steps
    std::string setting;           // e.g. "lut 256x64/32/192x108", for messages
    double predicted_error = 0;    // the table's p95 relative luminance error (worst corner)
    double predicted_seconds = 0;  // CPU s on the chart's machine, for this many directions
    bool meets_tolerance = false;
};

// Throws InvalidArgument for a tolerance outside [kMinTolerance, kMaxTolerance] (named
// "tolerance"), an invalid atmosphere or observer.
AutoChoice choose_sky_method(const Atmosphere& atmosphere, const Observer& observer, std::size_t directions,
                             double tolerance, const SkyOptions& options = {});

// The same choice from another table (tests use small synthetic ones).
AutoChoice choose_sky_method(const Atmosphere& atmosphere, const Observer& observer, std::size_t directions,
                             double tolerance, const SkyOptions& options, const auto_table::Table& table);

inline constexpr double kMinTolerance = 1e-3;
inline constexpr double kMaxTolerance = 10.0;

class AutoSky final : public SkyMethod {
public:
    // options.tolerance: the relative luminance error to meet (p95 over the sphere).
    explicit AutoSky(const SkyOptions& options = {});
    std::string name() const override { return "auto"; }
    void radiance(const Atmosphere& atmosphere, const Observer& observer,
                  std::span<const glm::dvec3> directions, std::span<float> out,
                  std::span<float> standard_error = {}, Progress* progress = nullptr) const override;

private:
    SkyOptions options_;
};

}  // namespace welkin
