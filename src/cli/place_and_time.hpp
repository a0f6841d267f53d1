// SPDX-License-Identifier: Apache-2.0
// --time, --latitude, --longitude, --height: the sun's (and the moon's) position from a
// place and a moment (welkin/astro/), for `welkin sun` and `welkin sky`.
#pragma once

#include <optional>
#include <string>

#include "common.hpp"
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"
#include "welkin/night/moonlit_sky.hpp"

namespace welkin::cli {

struct PlaceTimeArgs {
    std::string time;
    std::optional<double> latitude_deg, longitude_deg;
    double height_m = 0.0;
    CLI::App* app = nullptr;  // to see which of the observer's options were given
};

// Adds the options; call after add_observer_options (it refers to --sun-elevation and
// --sun-azimuth, which cannot be combined with --time).
void add_place_time_options(CLI::App* app, PlaceTimeArgs& args);

struct PlaceTime {
    CivilTime time;
    Place place;
    SunAndMoon sky;
    nlohmann::ordered_json json() const;
};

// None when no place-and-time option was given. Otherwise all of --time, --latitude and
// --longitude are required (InvalidArgument naming the missing one), and the observer's
// sun elevation and azimuth are set from the apparent sun (scene frame: +Y north, +X
// east; --sun-azimuth counts counter-clockwise from +X, so it is 90 - azimuth).
std::optional<PlaceTime> resolve_place_time(const PlaceTimeArgs& args, ObserverArgs& observer);

}  // namespace welkin::cli
