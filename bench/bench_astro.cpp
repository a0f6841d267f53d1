// SPDX-License-Identifier: Apache-2.0
// Positions of the sun and the moon (welkin/astro/): microseconds per call of
// sun_and_moon (both bodies, one precession-nutation, one place), over a year of moments.
//
//   build/welkin_bench_astro [--calls N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include <CLI/CLI.hpp>

#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"

using namespace welkin;

int main(int argc, char** argv) {
    CLI::App app{"Welkin positions bench"};
    int calls = 20000;
    app.add_option("--calls", calls, "calls per repeat")->check(CLI::Range(1, 10000000));
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
    return 0;
}
