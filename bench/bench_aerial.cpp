// SPDX-License-Identifier: Apache-2.0
// Aerial perspective at 1920 x 1080, side by side in one run: the froxel
// volume's build and its per-pixel application against marching every pixel to its
// depth, with the froxels' error against that march, for a few volume sizes.
//
// The frame: a camera 200 m up looking along +X, 2 degrees down, 35 mm lens, over a
// ground plane that runs out to a ridge 40-80 km away (the tops of the ridge against the
// sky), with a block of near objects (30-60 m) in the lower left; the sun 6 degrees up,
// ahead of the camera (Mie forward peak on screen). Errors over the non-sky pixels:
// in-scattering relative to the march (where the march exceeds 1e-3 of the frame's
// largest), transmittance absolute. Times are medians on this machine.
//
//   build/welkin_bench_aerial [--width 1920] [--height 1080] [--repeats 3] [--preset hazy]
//                             [--steps 64] [--csv FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "aerial_comparison.hpp"  // tests/cpp: the comparison the tests assert on
#include "bench_timing.hpp"
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/base/math.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;

namespace {

using bench::median_ms;

Camera camera_along_x(double height_m, double pitch_rad) {
    const double c = std::cos(pitch_rad), s = std::sin(pitch_rad);
    const glm::dvec3 forward{c, 0.0, -s}, up{s, 0.0, c}, right{0.0, -1.0, 0.0};
    Camera cam;
    cam.matrix_world = glm::dmat4(glm::dvec4(right, 0), glm::dvec4(up, 0), glm::dvec4(-forward, 0),
                                  glm::dvec4(0, 0, height_m, 1));
    cam.lens_mm = 35.0;
    cam.clip_end_m = 1e6;
    return cam;
}

std::vector<float> terrain_depth(const Camera& cam, int W, int H, double height_m) {
    const CameraRays rays(cam, W, H);
    std::vector<float> depth(std::size_t(W) * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const CameraRays::Ray r = rays.at_pixel(x, y);
            const double ridge = 60e3 + 20e3 * std::sin(6.0 * double(x) / W);
            const double ridge_top = 1500.0 + 600.0 * std::cos(11.0 * double(x) / W);
            double t;
            if (!(r.direction.z < 0.0 && (t = height_m / -r.direction.z) < ridge / r.direction.x)) {
                t = ridge / r.direction.x;
                if (height_m + t * r.direction.z > ridge_top) t = std::numeric_limits<double>::infinity();
            }
            if (x < W / 5 && y > 2 * H / 3)
                t = (30.0 + 30.0 * double(y - 2 * H / 3) / H) * r.distance_per_depth;
            depth[std::size_t(y) * W + x] = float(t / r.distance_per_depth);
        }
    return depth;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Welkin aerial-perspective benchmark"};
    int width = 1920, height = 1080, repeats = 3, steps = 64;
    std::string preset = "hazy", csv;
    app.add_option("--width", width, "render width in pixels");
    app.add_option("--height", height, "render height in pixels");
    app.add_option("--repeats", repeats, "runs per timing; the median is reported");
    app.add_option("--preset", preset, "atmosphere preset");
    app.add_option("--steps", steps, "per-pixel march: steps per ray");
    app.add_option("--csv", csv, "also write the figures as CSV");
    CLI11_PARSE(app, argc, argv);

    const double h0 = 200.0;
    SceneDescription scene;
    scene.atmosphere = Atmosphere::preset(preset);
    scene.camera = camera_along_x(h0, 2.0 * kDegree);
    scene.resolution = {width, height, 100};
    scene.sun_direction = sun_direction_from_angles_deg(6.0, 10.0);
    scene.aerial.raymarch_steps = steps;
    const std::vector<float> depth = terrain_depth(*scene.camera, width, height, h0);
    const double z_max = largest_finite_depth(depth, scene.aerial.sky_depth_m);
    fmt::print("Welkin aerial-perspective benchmark: {} threads, preset {}, {}x{}, depth up to {:.1f} km\n",
               tbb::info::default_concurrency(), preset, width, height, z_max / 1e3);

    AerialPasses reference;
    const double t_luts =
        median_ms(repeats, [&] { AtmosphereLuts luts(scene.atmosphere, scene.sky_options.luts()); });
    const double t_march = median_ms(
        1, [&] { reference = aerial_perspective_raymarch(scene.aerial_view(), depth, width, height); });
    fmt::print("  transmittance + multiple-scattering LUTs           {:9.2f} ms\n", t_luts);
    fmt::print("  per-pixel march ({} steps, LUTs included)          {:9.1f} ms\n", steps, t_march);

    std::FILE* out = nullptr;
    if (!csv.empty()) {
        out = std::fopen(csv.c_str(), "w");
        if (out)
            std::fprintf(
                out,
                "froxels,build_ms,apply_ms,total_ms,march_ms,median_rel_L,p99_rel_L,max_rel_L,max_abs_T\n");
    }
    const AtmosphereLuts luts(scene.atmosphere, scene.sky_options.luts());
    fmt::print("  {:>10} {:>10} {:>10} {:>10} {:>9} {:>11} {:>10} {:>10} {:>9}\n", "froxels", "build ms",
               "apply ms", "total ms", "speed-up", "L median %", "L p99 %", "L max %", "T max");
    for (const int n : {16, 32, 64}) {
        SceneDescription s = scene;
        s.aerial.froxel_width = s.aerial.froxel_height = s.aerial.froxel_slices = n;
        std::optional<AerialPerspectiveVolume> volume;
        const double t_build =
            median_ms(repeats, [&] { volume.emplace(s.aerial_view(), luts, width, height, z_max); });
        // The application: one volume lookup per pixel (the loop aerial_perspective_froxel runs).
        AerialPasses passes;
        passes.inscatter.resize(std::size_t(width) * height * 3);
        passes.transmittance.resize(passes.inscatter.size());
        const double t_apply = median_ms(repeats, [&] {
            tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
                for (int y = rows.begin(); y != rows.end(); ++y)
                    for (int x = 0; x < width; ++x) {
                        const std::size_t p = std::size_t(y) * width + x;
                        if (is_sky_depth(depth[p], s.aerial.sky_depth_m)) continue;
                        const auto smp = volume->sample((x + 0.5) / width, (y + 0.5) / height, depth[p]);
                        for (int c = 0; c < 3; ++c) {
                            passes.inscatter[p * 3 + c] = smp.inscatter[c];
                            passes.transmittance[p * 3 + c] = smp.transmittance[c];
                        }
                    }
            });
        });
        AerialPasses full;
        const double t_total = median_ms(
            repeats, [&] { full = aerial_perspective_froxel(s.aerial_view(), depth, width, height); });
        const test::AerialComparison e = test::compare_aerial_passes(full, reference, depth);
        fmt::print("  {:>10} {:10.2f} {:10.2f} {:10.2f} {:8.0f}x {:11.3f} {:10.3f} {:10.3f} {:9.5f}\n",
                   fmt::format("{0}x{0}x{0}", n), t_build, t_apply, t_total, t_march / t_total,
                   100 * e.median_rel_L, 100 * e.p99_rel_L, 100 * e.max_rel_L, e.max_abs_T);
        if (out)
            std::fprintf(out, "%d,%.3f,%.3f,%.3f,%.1f,%.6f,%.6f,%.6f,%.6f\n", n, t_build, t_apply, t_total,
                         t_march, e.median_rel_L, e.p99_rel_L, e.max_rel_L, e.max_abs_T);
    }
    if (out) std::fclose(out);
    fmt::print(
        "  (total: the whole froxel call, LUTs, volume and application included; errors "
        "against the per-pixel march)\n");
    return 0;
}
