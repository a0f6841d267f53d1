// SPDX-License-Identifier: Apache-2.0
// The sky of a place and a moment, for speed:
// - positions of the sun and the moon (welkin/astro/): microseconds per call of
//   sun_and_moon (both bodies, one precession-nutation, one place), over a year of moments;
// - night worlds against a clear day, side by side in one run: a width x width/2 RGB `lut`
//   image (default 2048 x 1024; LUTs cached, as when a lamp turns) of a clear day (the sun
//   30 degrees up, its disc and the lit ground), of a moonless night (La Palma, 2396 m,
//   2026-03-19 00:30 UTC, new moon) and of a full-moon night (Paris, 2026-12-24 01:00 CET,
//   the moon 68 degrees up), each night composed as welkin.sky_image_at and `welkin sky
//   --time` compose it (the sun's and the moon's skies, the moon's disc, the night glow, the
//   stars, their positions included). CPU time of the process (all threads), median of
//   --repeats runs, and each night's ratio to the clear day.
//
//   build/welkin_bench_astro [--calls N] [--width 2048] [--repeats 9]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_timing.hpp"
#include <CLI/CLI.hpp>
#include <tbb/info.h>

#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"
#include "welkin/night/moonlit_sky.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/night/stars.hpp"
#include "welkin/sky/lut.hpp"

using namespace welkin;

namespace {

// The night world of `time` at `where`, as welkin.sky_image_at composes it.
SkyImage night_world(const SkyMethod& method, const Atmosphere& atm, const std::string& time,
                     const Place& where, int width) {
    const Instant when = Instant::from_civil(parse_iso8601(time));
    const SunAndMoon positions = sun_and_moon(when, where);
    const auto& d = positions.sun.direction_enu;
    const Observer observer = Observer{0.0, {d[0], d[1], d[2]}}.validated();
    const SkyImageOptions options;
    SkyImage image = render_equirect_sky_with_moon(method, atm, observer, moon_at(positions), width, options);
    add_night_glow(image, atm, observer, options);
    add_stars(image, atm, observer, stars_at(when, where), options);
    return image;
}

void night_worlds(int width, int repeats) {
    const Atmosphere atm = Atmosphere::preset(kDefaultPreset);
    const LutSky lut(SkyOptions{}, LutSky::default_cache());
    const Observer day{0.0, {0.8660254037844387, 0.0, 0.5}};
    const Place la_palma{28.7606, -17.8816, 2396.0}, paris{48.8566, 2.3522, 35.0};
    render_equirect_sky(lut, atm, day, 256);  // the atmosphere's LUTs, built once
    const double clear = bench::median_cpu_s(repeats, [&] { render_equirect_sky(lut, atm, day, width); });
    const double moonless =
        bench::median_cpu_s(repeats, [&] { night_world(lut, atm, "2026-03-19T00:30:00Z", la_palma, width); });
    const double full_moon = bench::median_cpu_s(
        repeats, [&] { night_world(lut, atm, "2026-12-24T01:00:00+01:00", paris, width); });
    std::printf("%dx%d RGB lut worlds, %s, CPU time of the process (%d threads), median of %d:\n", width,
                width / 2, atm.name.c_str(), tbb::info::default_concurrency(), repeats);
    std::printf("  clear day (sun 30 deg up, disc, ground)          %7.3f s\n", clear);
    std::printf("  moonless night (La Palma, stars, glow)           %7.3f s  %.2fx the clear day\n", moonless,
                moonless / clear);
    std::printf("  full-moon night (Paris, moon 68 deg up, disc)    %7.3f s  %.2fx the clear day\n",
                full_moon, full_moon / clear);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Welkin positions bench"};
    int calls = 20000, width = 2048, repeats = 9;
    app.add_option("--calls", calls, "calls per repeat")->check(CLI::Range(1, 10000000));
    app.add_option("--width", width, "width of the night worlds (height = width / 2)")
        ->check(CLI::Range(4, 16384));
    app.add_option("--repeats", repeats, "runs per world timing; the median is reported")
        ->check(CLI::Range(1, 1000));
    CLI11_PARSE(app, argc, argv);

    const Place place{48.8566, 2.3522, 35.0};
    const Instant t0 = Instant::from_civil(parse_iso8601("2026-01-01T00:00:00Z"));
    std::vector<double> per_call_us;
    double sink = 0.0;
    for (int repeat = 0; repeat < 5; ++repeat) {
        const auto start = std::chrono::steady_clock::now();
        for (int i = 0; i < calls; ++i) {
            Instant t = t0;
            const double dt = 365.0 * i / calls;  // spread over a year
            t.tt2 += dt;
            t.ut12 += dt;
            const SunAndMoon r = sun_and_moon(t, place);
            sink += r.sun.elevation_deg + r.moon.elevation_deg;
        }
        const auto end = std::chrono::steady_clock::now();
        per_call_us.push_back(std::chrono::duration<double, std::micro>(end - start).count() / calls);
    }
    std::sort(per_call_us.begin(), per_call_us.end());
    std::printf(
        "sun_and_moon: median %.2f us per call (min %.2f, max %.2f; 5 x %d calls, one thread)  [%g]\n",
        per_call_us[2], per_call_us[0], per_call_us[4], calls, sink * 0.0);
    night_worlds(width, repeats);
    return 0;
}
