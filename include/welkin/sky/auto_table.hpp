// SPDX-License-Identifier: Apache-2.0
// The measured table the "auto" sky method chooses from (see sky/auto.hpp).
//
// Its numbers are not written by hand: bench/chart.py measures every method and setting
// against the reference on a grid of scenes (observer altitude x sun elevation x preset)
// and writes src/sky/auto_table.cpp. Rerun the chart (and rebuild) whenever a method's
// speed or accuracy changes:
//     PYTHONPATH=build /usr/bin/python3 bench/chart.py
//
// Thread safety: the table is immutable static data.
#pragma once

#include <cstddef>
#include <limits>
#include <span>

namespace welkin::auto_table {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// One charted method and setting, with its measured cost on the machine the chart ran on,
// in CPU seconds (all threads summed; see bench/chart.py):
// a call on N directions takes about fixed_seconds + seconds_per_direction * N.
struct Setting {
    const char* method;  // "analytic" | "lut" | "raymarch"
    bool spectral;       // measured at the chart's spectral sampling (else 3 wavelengths)
    int transmittance_width, transmittance_height, multiscattering_size;
    int skyview_width, skyview_height;
    int raymarch_steps, raymarch_sun_steps;
    double fixed_seconds;
    double seconds_per_direction;
};

struct Table {
    std::span<const double> altitudes_m;         // ascending
    std::span<const double> sun_elevations_deg;  // ascending
    std::span<const char* const> presets;
    std::span<const Setting> settings;
    // 95th percentile over the sphere of the relative luminance error against the
    // reference, [preset][setting][altitude][sun elevation]; kInf where the method gave a
    // non-finite or negative value.
    const double* p95;
    // The reference's own p95 relative standard error, [preset][altitude][sun elevation].
    const double* reference_noise;
    int reference_paths;
    double reference_seconds_per_path;

    double p95_at(std::size_t preset, std::size_t setting, std::size_t altitude, std::size_t sun) const {
        return p95[((preset * settings.size() + setting) * altitudes_m.size() + altitude) *
                       sun_elevations_deg.size() +
                   sun];
    }
};

// The table compiled into this build (src/sky/auto_table.cpp, generated).
const Table& table();

}  // namespace welkin::auto_table
