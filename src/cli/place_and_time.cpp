// SPDX-License-Identifier: Apache-2.0
// Place-and-time options of `welkin sun` and `welkin sky` (place_and_time.hpp).
#include "place_and_time.hpp"

#include <cmath>

#include "welkin/astro/json.hpp"
#include "welkin/base/error.hpp"

namespace welkin::cli {

void add_place_time_options(CLI::App* app, PlaceTimeArgs& args) {
    args.app = app;
    app->add_option("--time", args.time,
                    "Moment, ISO 8601 with its UTC offset (2026-06-21T21:30:00+02:00 or "
                    "...Z), years 1900-2100: the sun and the moon from --latitude/--longitude "
                    "then (replaces --sun-elevation/--sun-azimuth, or a --scene's sun; +Y is north, +X "
                    "east)")
        ->type_name("ISO8601");
    app->add_option("--latitude", args.latitude_deg, "Geodetic latitude, degrees north in [-90, 90]")
        ->type_name("DEG");
    app->add_option("--longitude", args.longitude_deg, "Longitude, degrees east in [-180, 180]")
        ->type_name("DEG");
    app->add_option("--height", args.height_m,
                    "Height of the place above sea level, metres in [-500, 100000] (refraction, "
                    "parallax; with --time)")
        ->type_name("M")
        ->capture_default_str();
}

nlohmann::ordered_json PlaceTime::json() const { return place_and_time_json(time, place, sky); }

std::optional<PlaceTime> resolve_place_time(const PlaceTimeArgs& args, ObserverArgs& observer) {
    const auto given = [&](const char* name) { return args.app && args.app->get_option(name)->count() > 0; };
    const bool any = given("--time") || given("--latitude") || given("--longitude") || given("--height");
    if (!any) return std::nullopt;
    if (!given("--time")) throw InvalidArgument("--time", "is required with --latitude/--longitude/--height");
    if (!args.latitude_deg) throw InvalidArgument("--latitude", "is required with --time");
    if (!args.longitude_deg) throw InvalidArgument("--longitude", "is required with --time");
    for (const char* name : {"--sun-elevation", "--sun-azimuth"})
        if (given(name))
            throw InvalidArgument(name,
                                  "cannot be combined with --time (the sun's position comes from the place "
                                  "and the time)");
    require_in_range("--latitude", *args.latitude_deg, -90.0, 90.0, "degrees");
    require_in_range("--longitude", *args.longitude_deg, -180.0, 180.0, "degrees");
    require_in_range("--height", args.height_m, -500.0, 100000.0, "m");
    PlaceTime out;
    out.time = parse_iso8601(args.time, "--time");
    out.place = Place{*args.latitude_deg, *args.longitude_deg, args.height_m};
    out.sky = sun_and_moon(Instant::from_civil(out.time, "--time"), out.place);
    observer.sun_elevation_deg = out.sky.sun.elevation_deg;
    double azimuth = 90.0 - out.sky.sun.azimuth_deg;  // counter-clockwise from +X, (-270, 90]
    if (azimuth <= -180.0) azimuth += 360.0;          // (-180, 180]
    observer.sun_azimuth_deg = azimuth;
    return out;
}

}  // namespace welkin::cli
