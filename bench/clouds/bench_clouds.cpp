// Speed and accuracy of the cloud lighting (issue #6), side by side in one run:
//  * a 2048 x 1024 equirectangular sky (lut) clear and with a procedural cumulus layer;
//  * the fast march against the path-tracing reference on three clouds (a thin wispy
//    layer, a dense cumulus layer, a VDB ball written here with OpenVDB): the error of the
//    mean radiance (bias), the mean absolute error per view, the largest transmittance
//    difference, and both times, for the march at its defaults and at a finer setting.
// Timings are medians of repeated runs on this machine.
//
//   build/welkin_bench_clouds [--width 2048] [--repeats 3] [--csv FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <tbb/info.h>
#include <unistd.h>

#include "../bench_timing.hpp"
#include "welkin/cloud_illumination.hpp"
#include "welkin/cloud_lighting.hpp"
#include "welkin/cloud_noise.hpp"
#include "welkin/cloud_reference.hpp"
#include "welkin/math.hpp"
#include "welkin/procedural_clouds.hpp"
#include "welkin/sky_image.hpp"
#include "welkin/vdb_clouds.hpp"

using namespace welkin;
using Clock = std::chrono::steady_clock;

namespace {

using bench::median_s;

std::vector<glm::dvec3> view_grid(glm::dvec3 centre, double half_angle, int k) {
    centre = glm::normalize(centre);
    const glm::dvec3 a = glm::normalize(glm::cross(centre, glm::dvec3(0, 0, 1)));
    const glm::dvec3 b = glm::cross(centre, a);
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i)
            dirs.push_back(glm::normalize(centre + (2.0 * (i + 0.5) / k - 1.0) * std::tan(half_angle) * a +
                                          (2.0 * (j + 0.5) / k - 1.0) * std::tan(half_angle) * b));
    return dirs;
}

std::string write_ball_vdb() {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::createLinearTransform(10.0));
    auto acc = grid->getAccessor();
    for (int k = -21; k <= 21; ++k)
        for (int j = -21; j <= 21; ++j)
            for (int i = -21; i <= 21; ++i) {
                const double r = std::sqrt(double(i * i + j * j + k * k)) / 20.0;
                if (r >= 1.0) continue;
                const double w = tileable_worley((i + 21) / 42.0, (j + 21) / 42.0, (k + 21) / 42.0, 4, 3);
                acc.setValue(openvdb::Coord(i, j, k), float((1.0 - r * r) * (0.3 + 0.7 * w)));
            }
    const std::string path =
        (std::filesystem::temp_directory_path() / fmt::format("welkin_bench_cloud_{}.vdb", ::getpid())).string();
    openvdb::io::File file(path);
    file.write({grid});
    file.close();
    return path;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Welkin cloud benchmark"};
    int width = 2048, repeats = 3;
    std::string csv;
    app.add_option("--width", width, "sky width in pixels (height = width / 2)");
    app.add_option("--repeats", repeats, "runs per timing; the median is reported");
    app.add_option("--csv", csv, "also write the figures as CSV");
    bool sky_only = false;
    app.add_flag("--sky-only", sky_only, "only the sky timings (for profiling)");
    CLI11_PARSE(app, argc, argv);
    std::vector<std::string> rows;

    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const Observer obs{0.0, glm::normalize(glm::dvec3(0.6, 0.2, 0.5))};
    fmt::print("Welkin cloud benchmark: {} threads, {}x{} sky\n", tbb::info::default_concurrency(), width, width / 2);

    // --- the cloudy sky ---------------------------------------------------------------
    CloudLayerParams cumulus;
    cumulus.coverage = 0.6;
    cumulus.density_per_m = 0.03;
    const auto t_bake0 = Clock::now();
    auto layer = std::make_shared<const ProceduralClouds>(cumulus);
    const double bake = std::chrono::duration<double>(Clock::now() - t_bake0).count();
    const auto lut = make_sky_method("lut");
    SkyImageOptions clear;
    SkyImageOptions cloudy;
    cloudy.clouds = layer;
    const double t_clear = median_s(repeats, [&] { render_equirect_sky(*lut, atm, obs, width, clear); });
    const double t_cloudy = median_s(repeats, [&] { render_equirect_sky(*lut, atm, obs, width, cloudy); });
    fmt::print("\n| what | time |\n|---|---|\n");
    fmt::print("| noise bake (once per seed) | {:.2f} s |\n", bake);
    fmt::print("| lut sky {}x{}, clear | {:.3f} s |\n", width, width / 2, t_clear);
    fmt::print("| lut sky {}x{}, cumulus layer (defaults: 96 + 8 steps, 4 octaves) | {:.3f} s |\n", width, width / 2,
               t_cloudy);
    rows.push_back(fmt::format("sky,{},clear,{:.4f},,,,,", width, t_clear));
    rows.push_back(fmt::format("sky,{},cumulus,{:.4f},,,,,", width, t_cloudy));

    if (sky_only) return 0;

    // --- fast vs reference --------------------------------------------------------------
    const double e = 35.0 * kDegree;
    const ConstantIllumination light({std::cos(e), 0.0, std::sin(e)}, {1.0f, 1.0f, 1.0f}, {0.04f, 0.04f, 0.04f});
    CloudLayerParams thin;
    thin.bottom_altitude_m = 1500.0;
    thin.top_altitude_m = 2300.0;
    thin.coverage = 0.55;
    thin.cloud_type = 0.5;
    thin.density_per_m = 0.004;
    thin.detail_strength = 0.6;
    CloudLayerParams dense;
    dense.bottom_altitude_m = 1500.0;
    dense.top_altitude_m = 2700.0;
    dense.coverage = 0.75;
    dense.density_per_m = 0.03;
    const ProceduralClouds thin_layer(thin), dense_layer(dense);
    const std::string vdb_path = write_ball_vdb();
    VdbCloudOptions vo;
    vo.matrix_world = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 1500.0, 900.0));
    vo.density_scale = 0.03;
    const VdbClouds vdb(vdb_path, vo);
    std::filesystem::remove(vdb_path);

    struct Case {
        const char* name;
        const CloudDensity& density;
        std::vector<glm::dvec3> dirs;
        int paths;
    };
    const std::vector<Case> cases = {{"thin wispy", thin_layer, view_grid({0.3, 0.4, 1.0}, 0.5, 6), 8192},
                                     {"dense cumulus", dense_layer, view_grid({0.3, 0.4, 1.0}, 0.5, 6), 512},
                                     {"vdb", vdb, view_grid({0.0, 1500.0, 900.0}, 0.12, 6), 2048}};
    CloudLightingOptions fine;
    fine.max_steps = 512;
    fine.light_steps = 32;
    fine.ambient_steps = 16;
    fmt::print("\n| case | march | bias | mean abs err | max dT | ref se | march time | reference time (paths) |\n");
    fmt::print("|---|---|---|---|---|---|---|---|\n");
    for (const Case& c : cases) {
        CloudReferenceOptions ro;
        ro.paths = c.paths;
        CloudReferenceResult ref;
        const double t_ref = median_s(1, [&] { ref = render_clouds_reference(c.density, light, {0, 0, 0}, c.dirs, ro); });
        for (const auto& [label, opt] : {std::pair{"default", CloudLightingOptions{}}, std::pair{"fine", fine}}) {
            CloudResult fast;
            const double t_fast = median_s(repeats, [&] { fast = render_clouds(c.density, light, {0, 0, 0}, c.dirs, opt); });
            double sf = 0, sr = 0, sa = 0, var = 0, dT = 0;
            for (std::size_t r = 0; r < c.dirs.size(); ++r) {
                sf += fast.radiance[r * 3 + 1];
                sr += ref.radiance[r * 3 + 1];
                sa += std::abs(fast.radiance[r * 3 + 1] - ref.radiance[r * 3 + 1]);
                var += double(ref.radiance_error[r * 3 + 1]) * ref.radiance_error[r * 3 + 1];
                dT = std::max(dT, std::abs(double(fast.transmittance[r]) - ref.transmittance[r]));
            }
            const double bias = sf / sr - 1.0, mae = sa / sr, se = std::sqrt(var) / sr;
            fmt::print("| {} | {} | {:+.1f} % | {:.1f} % | {:.3f} | {:.1f} % | {:.4f} s | {:.2f} s ({}) |\n", c.name,
                       label, 100 * bias, 100 * mae, dT, 100 * se, t_fast, t_ref, c.paths);
            rows.push_back(fmt::format("case,{},{},{:.5f},{:.5f},{:.5f},{:.5f},{:.4f},{}", c.name, label, t_fast, bias,
                                       mae, dT, t_ref, c.paths));
        }
    }
    fmt::print("({} views per case; sun 35 deg, constant sun and sky light; green channel)\n", cases[0].dirs.size());
    if (!csv.empty()) {
        if (std::filesystem::exists(csv)) {
            fmt::print(stderr, "--csv: {} exists; not overwritten\n", csv);
            return 1;
        }
        std::ofstream f(csv);
        f << "kind,name,variant,time_s,bias,mean_abs_error,max_dT,reference_time_s,paths\n";
        for (const auto& r : rows) f << r << "\n";
    }
    return 0;
}
