// SPDX-License-Identifier: Apache-2.0
// Speed of the sky pipeline, side by side in one run: each LUT's build time, a
// full LUT rebuild, a 2048 x 1024 equirectangular sky by lut (all LUTs built in the call,
// and as a sun change with the atmosphere's LUTs cached), raymarch and reference, with
// speed-up ratios. Timings are medians of repeated runs on this machine;
// the reference is timed on a strided subset of the image's pixels and extrapolated
// (printed as such), since a full-image Monte-Carlo render takes hours on two cores.
//
//   build/welkin_bench [--width 2048] [--repeats 31] [--reference-stride 4096] [--csv FILE]
//
// 31 repeats by default: the LUT rows take milliseconds, and on a shared machine the
// median of a few runs moves with the neighbours (raymarch is timed min(repeats, 3) times).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <vector>

#include "bench_timing.hpp"
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "welkin/atmosphere/lut_cache.hpp"
#include "welkin/atmosphere/luts.hpp"
#include "welkin/atmosphere/skyview_lut.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/sky/lut.hpp"
#include "welkin/sky/method.hpp"

using namespace welkin;

using bench::median_ms;

namespace {

// One run's settings and its rows (what, median ms), printed as they come.
struct SkyBench {
    int width = 2048, repeats = 31, stride = 4096;
    Atmosphere atm = Atmosphere::preset("bruneton2017");
    SkyOptions options;
    Observer observer{0.0, glm::normalize(glm::dvec3(0.5, 0.3, 0.4))};
    double r = atm.bottom_radius_m + observer.altitude_m;
    std::vector<std::pair<std::string, double>> rows;

    void report(const std::string& what, double ms) {
        rows.emplace_back(what, ms);
        fmt::print("  {:<52} {:>10.2f} ms\n", what, ms);
    }

    // Each LUT's build, then full rebuilds on the ground and 1 km up.
    void luts() {
        // LUT builds, one at a time.
        const AtmosphereBatch medium(atm, 0, atm.channels());
        report(
            fmt::format("transmittance LUT {}x{}", options.transmittance_width, options.transmittance_height),
            median_ms(repeats, [&] {
                TransmittanceLut t(medium, options.transmittance_width, options.transmittance_height);
            }));
        const TransmittanceLut tlut(medium, options.transmittance_width, options.transmittance_height);
        report(fmt::format("multiple-scattering LUT {}x{}", options.multiscattering_size,
                           options.multiscattering_size),
               median_ms(repeats, [&] { MultiScatteringLut m(medium, tlut, options.multiscattering_size); }));
        const MultiScatteringLut mslut(medium, tlut, options.multiscattering_size);
        report(fmt::format("sky-view LUT {}x{}", options.skyview_width, options.skyview_height),
               median_ms(repeats, [&] {
                   SkyViewLut s(medium, tlut, mslut, r, observer.sun_direction.z, options.skyview_width,
                                options.skyview_height);
               }));
        report("full LUT rebuild (atmosphere change: all three)", median_ms(repeats, [&] {
                   AtmosphereBatch m(atm, 0, atm.channels());
                   TransmittanceLut t(m, options.transmittance_width, options.transmittance_height);
                   MultiScatteringLut ms(m, t, options.multiscattering_size);
                   SkyViewLut s(m, t, ms, r, observer.sun_direction.z, options.skyview_width,
                                options.skyview_height);
               }));
        // From the ground itself the sky-view rows below the horizon are rays of no length
        // (no steps); 1 km up they cross air too, so this is the rebuild of an elevated camera.
        report("full LUT rebuild, observer 1 km up", median_ms(repeats, [&] {
                   AtmosphereBatch m(atm, 0, atm.channels());
                   TransmittanceLut t(m, options.transmittance_width, options.transmittance_height);
                   MultiScatteringLut ms(m, t, options.multiscattering_size);
                   SkyViewLut s(m, t, ms, r + 1000.0, observer.sun_direction.z, options.skyview_width,
                                options.skyview_height);
               }));
    }

    // The number of wavelengths: LUT rebuilds and RGB sky images.
    void colour() {
        // Colour: the default four wavelengths (620/560/480/440 nm, fitted conversion) beside
        // the three of Bruneton 2017 (680/550/440 nm) they replaced, side by side: the full LUT
        // rebuild and a 2048 x 1024 RGB sky image (render_equirect_sky with the lut method, all
        // LUTs built in the call, the disc included).
        {
            const Atmosphere three = Atmosphere::preset("bruneton2017", {680.0, 550.0, 440.0});
            auto rebuild = [&](const Atmosphere& a) {
                return median_ms(repeats, [&] {
                    AtmosphereBatch m(a, 0, a.channels());
                    TransmittanceLut t(m, options.transmittance_width, options.transmittance_height);
                    MultiScatteringLut ms(m, t, options.multiscattering_size);
                    SkyViewLut s(m, t, ms, r, observer.sun_direction.z, options.skyview_width,
                                 options.skyview_height);
                });
            };
            const LutSky uncached(options, nullptr);
            auto image = [&](const Atmosphere& a) {
                return median_ms(std::max(3, repeats / 4),
                                 [&] { render_equirect_sky(uncached, a, observer, width); });
            };
            const Atmosphere eight =
                Atmosphere::preset("bruneton2017", {680.0, 640.0, 600.0, 560.0, 520.0, 480.0, 440.0, 400.0});
            const double r3 = rebuild(three), r4 = rebuild(atm);
            double r8 = 0.0;
            {
                r8 = median_ms(repeats, [&] {
                    for (std::size_t first = 0; first < 8; first += 4) {
                        AtmosphereBatch m(eight, first, 4);
                        TransmittanceLut t(m, options.transmittance_width, options.transmittance_height);
                        MultiScatteringLut ms(m, t, options.multiscattering_size);
                        SkyViewLut s(m, t, ms, r, observer.sun_direction.z, options.skyview_width,
                                     options.skyview_height);
                    }
                });
            }
            report("full LUT rebuild, 3 wavelengths (680/550/440)", r3);
            report("full LUT rebuild, default 4 wavelengths", r4);
            report("full LUT rebuild, 8 wavelengths (two batches)", r8);
            const double i3 = image(three), i4 = image(atm), i8 = image(eight);
            report(fmt::format("{}x{} RGB sky image, 3 wavelengths", width, width / 2), i3);
            report(fmt::format("{}x{} RGB sky image, default 4 wavelengths", width, width / 2), i4);
            report(fmt::format("{}x{} RGB sky image, 8 wavelengths", width, width / 2), i8);
            fmt::print("  colour: 4 / 3 wavelengths: LUT rebuild {:.2f}x, image {:.2f}x\n", r4 / r3, i4 / i3);
            fmt::print("  colour: 8 / 3 wavelengths: LUT rebuild {:.2f}x, image {:.2f}x\n", r8 / r3, i8 / i3);
        }
    }

    // Whole-image skies through the SkyMethod interface: lut (uncached and a sun change),
    // raymarch, and the reference extrapolated from every stride-th pixel.
    void methods() {
        // Whole-image skies through the SkyMethod interface.
        const int height = width / 2;
        std::vector<glm::dvec3> dirs(std::size_t(width) * height);
        for (int j = 0; j < height; ++j)
            for (int i = 0; i < width; ++i)
                dirs[std::size_t(j) * width + i] = equirect_pixel_direction(i, j, width, height);
        std::vector<float> out(dirs.size() * atm.channels());
        // The lut method keeps the atmosphere's LUTs between calls (lut_cache.hpp). Timed twice:
        // with every LUT built in the call (no cache), and as a sun change (a warm cache: the
        // sky-view LUT plus the lookups), moving the sun on every repeat.
        const LutSky lut(options, nullptr);
        const double lut_ms = median_ms(repeats, [&] { lut.radiance(atm, observer, dirs, out); });
        report(fmt::format("lut {}x{} sky (all LUTs built in the call, no file)", width, height), lut_ms);
        AtmosphereLutCache cache;
        const LutSky lut_cached(options, &cache);
        lut_cached.radiance(atm, observer, dirs, out);
        int turn = 0;
        const double sun_change_ms = median_ms(repeats, [&] {
            const double azimuth = 0.1 * ++turn, elevation = 0.4 + 0.01 * turn;
            const Observer moved{observer.altitude_m,
                                 glm::dvec3(std::cos(elevation) * std::cos(azimuth),
                                            std::cos(elevation) * std::sin(azimuth), std::sin(elevation))};
            lut_cached.radiance(atm, moved, dirs, out);
        });
        report(fmt::format("sun change: sky-view + {}x{} lookups (cached LUTs)", width, height),
               sun_change_ms);
        if (cache.builds() != 1) fmt::print("  (the cache rebuilt {} times: unexpected)\n", cache.builds());
        const auto raymarch = make_sky_method("raymarch", options);
        const double raymarch_ms =
            median_ms(std::min(repeats, 3), [&] { raymarch->radiance(atm, observer, dirs, out); });
        report(fmt::format("raymarch {}x{} sky ({} + {} steps)", width, height, options.raymarch_steps,
                           options.raymarch_sun_steps),
               raymarch_ms);
        std::vector<glm::dvec3> subset;
        for (std::size_t i = 0; i < dirs.size(); i += std::size_t(stride)) subset.push_back(dirs[i]);
        std::vector<float> out_subset(subset.size() * atm.channels());
        fmt::print("  speed-up lut vs raymarch:  {:>8.0f}x\n", raymarch_ms / lut_ms);
        try {
            const auto reference = make_sky_method("reference", options);
            const double ref_subset_ms =
                median_ms(1, [&] { reference->radiance(atm, observer, subset, out_subset); });
            const double reference_ms = ref_subset_ms * double(dirs.size()) / double(subset.size());
            report(fmt::format("reference {}x{} sky ({} paths; extrapolated from {} px)", width, height,
                               options.reference_paths, subset.size()),
                   reference_ms);
            fmt::print("  speed-up lut vs reference: {:>8.0f}x\n", reference_ms / lut_ms);
        } catch (const std::exception& e) {
            fmt::print("  reference: not timed ({})\n", e.what());
        }
    }

    void write_csv(const std::string& path) const {
        std::ofstream f(path);
        f << "what,ms\n";
        for (auto& [what, ms] : rows) f << '"' << what << "\"," << ms << '\n';
    }
};

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Welkin sky benchmark"};
    SkyBench bench;
    std::string csv;
    app.add_option("--width", bench.width, "HDRI width in pixels (height = width / 2)");
    app.add_option("--repeats", bench.repeats, "runs per timing; the median is reported");
    app.add_option("--reference-stride", bench.stride, "time the reference on every Nth pixel");
    app.add_option("--csv", csv, "also write the figures as CSV");
    CLI11_PARSE(app, argc, argv);
    fmt::print("Welkin sky benchmark: {} threads, preset {}, {}x{} sky\n", tbb::info::default_concurrency(),
               bench.atm.name, bench.width, bench.width / 2);
    bench.luts();
    bench.colour();
    bench.methods();
    if (!csv.empty()) bench.write_csv(csv);
    return 0;
}
