// SPDX-License-Identifier: Apache-2.0
// The positions of one place and moment as JSON: the object `place_and_time` that
// `welkin sun --time ...` prints and welkin.sun_and_moon() returns (as a dict), one schema
// for both (docs/reference.md#place-and-time).
#pragma once

#include <nlohmann/json.hpp>

#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"

namespace welkin {

// {"time", "utc", "tt_jd", "ut1_jd", "delta_t_s", "latitude_deg", "longitude_deg",
//  "height_m", "pressure_hpa", "temperature_c",
//  "sun":  {"elevation_deg", "azimuth_deg", "airless_elevation_deg", "distance_m",
//           "angular_radius_deg", "right_ascension_deg", "declination_deg", "direction"},
//  "moon": {the same, and "phase_angle_deg", "illuminated_fraction", "age_angle_deg",
//           "irradiance_ratio", "sun_direction_from_moon"}}
// Directions are unit vectors in the scene frame with north along +Y: x east, y north,
// z up. `time` is the civil time as given (ISO 8601 with its offset), `utc` the same
// moment in UTC.
nlohmann::ordered_json place_and_time_json(const CivilTime& time, const Place& place, const SunAndMoon& sky);

// ISO 8601 in UTC ("2026-06-21T19:30:00Z"; fractional seconds to the microsecond when
// there are any) and with its own offset ("2026-06-21T21:30:00+02:00").
std::string format_iso8601_utc(const CivilTime& time);
std::string format_iso8601(const CivilTime& time);

}  // namespace welkin
