// SPDX-License-Identifier: Apache-2.0
// place_and_time JSON (include/welkin/astro/json.hpp).
#include "welkin/astro/json.hpp"

#include <cmath>

#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {
namespace {

std::string format_clock(const CivilTime& t) {
    const double whole = std::floor(t.second);
    const long micro = std::lround((t.second - whole) * 1e6);
    std::string s = fmt::format("{:04d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}", t.year, t.month, t.day, t.hour,
                                t.minute, int(whole));
    if (micro > 0) s += fmt::format(".{:06d}", std::min(micro, 999999L));
    return s;
}

nlohmann::ordered_json body_json(const CelestialPosition& p) {
    return {{"elevation_deg", p.elevation_deg},
            {"azimuth_deg", p.azimuth_deg},
            {"airless_elevation_deg", p.airless_elevation_deg},
            {"distance_m", p.distance_m},
            {"angular_radius_deg", p.angular_radius_deg},
            {"right_ascension_deg", p.right_ascension_deg},
            {"declination_deg", p.declination_deg},
            {"direction", p.direction_enu}};
}

}  // namespace

std::string format_iso8601_utc(const CivilTime& time) { return format_clock(to_utc(time)) + "Z"; }

std::string format_iso8601(const CivilTime& time) {
    const int off = time.utc_offset_minutes, a = std::abs(off);
    return format_clock(time) + fmt::format("{}{:02d}:{:02d}", off < 0 ? '-' : '+', a / 60, a % 60);
}

nlohmann::ordered_json place_and_time_json(const CivilTime& time, const Place& place, const SunAndMoon& sky) {
    nlohmann::ordered_json moon = body_json(sky.moon);
    moon["phase_angle_deg"] = sky.moon_phase_angle_deg;
    moon["illuminated_fraction"] = sky.moon_illuminated_fraction;
    moon["age_angle_deg"] = sky.moon_age_angle_deg;
    moon["irradiance_ratio"] = sky.moon_irradiance_ratio;
    moon["sun_direction_from_moon"] = sky.sun_from_moon_enu;
    return {{"time", format_iso8601(time)},
            {"utc", format_iso8601_utc(time)},
            {"tt_jd", sky.tt_jd},
            {"ut1_jd", sky.ut1_jd},
            {"delta_t_s", sky.delta_t_s},
            {"latitude_deg", place.latitude_deg},
            {"longitude_deg", place.longitude_deg},
            {"height_m", place.height_m},
            {"pressure_hpa", place.effective_pressure_hpa()},
            {"temperature_c", place.temperature_c},
            {"sun", body_json(sky.sun)},
            {"moon", moon}};
}

}  // namespace welkin
