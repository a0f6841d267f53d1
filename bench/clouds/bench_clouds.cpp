// SPDX-License-Identifier: Apache-2.0
// Speed and accuracy of the cloud lighting, side by side in one run:
//  * a 2048 x 1024 equirectangular sky (lut) clear and with a procedural cumulus layer;
//  * the fast march against the path-tracing reference on three clouds (a thin wispy
//    layer, a dense cumulus layer, a VDB ball written here with OpenVDB): the error of the
//    mean radiance (bias), the mean absolute error per view, the largest transmittance
//    difference, and the time per million rays, for the march at five quality settings
//    and as it was before the optical-depth grid ("legacy"), and for the reference at
//    fewer paths (its noise for its time); bench/clouds/chart.py draws them;
//  * a 1920 x 1080 camera view of the VDB, the march at its defaults and legacy;
//  * the optical-depth grid against a shadow ray per sample on a cloudy sky's rays.
// Timings are medians of repeated runs on this machine.
//
//   build/welkin_bench_clouds [--width 2048] [--repeats 3] [--csv FILE] [--sky-only]
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "../bench_timing.hpp"
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <tbb/info.h>
#include <unistd.h>

#include "welkin/base/math.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/noise.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/reference.hpp"
#include "welkin/clouds/vdb.hpp"
#include "welkin/render/sky_image.hpp"

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
        (std::filesystem::temp_directory_path() / fmt::format("welkin_bench_cloud_{}.vdb", ::getpid()))
            .string();
    openvdb::io::File file(path);
    file.write({grid});
    file.close();
    return path;
}

// The figures as CSV (the sky rows: kind "sky", variant, time_s, then the mean and 99th
// percentile error against the exact image in the bias and mean_abs_error columns).
int write_csv(const std::string& csv, const std::vector<std::string>& rows) {
    if (csv.empty()) return 0;
    if (std::filesystem::exists(csv)) {
        fmt::print(stderr, "--csv: {} exists; not overwritten\n", csv);
        return 1;
    }
    std::ofstream f(csv);
    // bias .. paths: the fast-vs-reference cases; mean_error, p99_error: the cloudy sky
    // against its converged march.
    f << "kind,name,variant,time_s,bias,mean_abs_error,max_dT,reference_time_s,paths,mean_error,p99_error\n";
    for (const auto& r : rows) f << r << "\n";
    return 0;
}

// The command line.
struct Args {
    int width = 2048, repeats = 3, reference_seeds = 4;
    std::string csv;
    bool sky_only = false, cases_only = false, types_only = false;
    double spread = 0.0;
    std::string only_type, upsampling_type;
};

void add_options(CLI::App& app, Args& a) {
    app.add_option("--width", a.width, "sky width in pixels (height = width / 2)");
    app.add_option("--repeats", a.repeats, "runs per timing; the median is reported");
    app.add_option("--reference-seeds", a.reference_seeds,
                   "exact cloudy skies averaged into the converged reference of the upsampling's error")
        ->check(CLI::Range(1, 64));
    app.add_option("--csv", a.csv, "also write the figures as CSV");
    app.add_flag("--sky-only", a.sky_only, "only the sky timings (for profiling)");
    app.add_flag("--types-only", a.types_only, "only every cloud type's sky, side by side");
    app.add_option("--ray-spread", a.spread,
                   "the types' skies: CloudLightingOptions::ray_spread_rad (0: from the grid; 1e-9: "
                   "the grids' levels by the view step alone)");
    app.add_option("--type", a.only_type, "the types' skies: this type only");
    app.add_option("--upsampling-type", a.upsampling_type,
                   "the upsampling's table for this type's preset instead of the default layer (the "
                   "types' skies then skipped)")
        ->check(CLI::IsMember(std::vector<std::string>(kCloudTypeNames.begin(), kCloudTypeNames.end())));
    app.add_flag("--cases-only", a.cases_only, "only fast vs reference on the three clouds, at the defaults");
}

// --- every type side by side ---------------------------------------------------------
// The sky of `o` rendered once with the sun of obs, then again (median of repeats) with the
// sun turned 10 degrees in azimuth more each time, the clouds' view samples kept
// (CloudViewCache): the seconds of one again, and the cache's bytes.
std::array<double, 2> relight_s(const Args& a, const SkyMethod& lut, const Atmosphere& atm,
                                const Observer& obs, SkyImageOptions o) {
    auto cache = std::make_shared<CloudViewCache>();
    cache->keep("bench");
    o.cloud_lighting.view_cache = cache;
    render_equirect_sky(lut, atm, obs, a.width, o);
    Observer turned = obs;
    const glm::dvec3 s = obs.sun_direction;
    double azimuth = std::atan2(s.y, s.x);
    const double t = median_s(a.repeats, [&] {
        azimuth += 10.0 * kDegree;
        const double h = std::hypot(s.x, s.y);
        turned.sun_direction = {h * std::cos(azimuth), h * std::sin(azimuth), s.z};
        render_equirect_sky(lut, atm, turned, a.width, o);
    });
    return {t, double(cache->bytes())};
}

// Each type at its preset, as `welkin sky --scene` renders it: the layer's build (the
// coverage calibration; the noise bake, shared by every type of a seed, is timed once
// before) and the 2048 x 1024 sky with the default upsampling.
void bench_types(const Args& a, const Atmosphere& atm, const Observer& obs, std::vector<std::string>& rows) {
    CloudLayerParams clear_layer;  // coverage 0: the noise bake without a calibration
    clear_layer.coverage = 0.0;
    const double t_noise = median_s(1, [&] { ProceduralClouds warm(clear_layer); });
    fmt::print(
        "\n| type | layer build | sky {}x{} | total | sky's CPU time (all threads) |\n"
        "|---|---|---|---|---|\n",
        a.width, a.width / 2);
    fmt::print("| (noise bake, once per seed) | {:.2f} s | | |\n", t_noise);
    const auto type_lut = make_sky_method("lut");
    std::vector<std::array<double, 3>> totals;  // per type: wall, CPU / 2 (two idle cores), type index
    std::vector<std::array<double, 2>> relit;   // per type: the sky lit again, the cache's bytes
    for (std::size_t t = 0; t < kCloudTypeNames.size(); ++t) {
        if (!a.only_type.empty() && a.only_type != kCloudTypeNames[t]) continue;
        CloudLayerParams p = CloudLayerParams::preset(static_cast<CloudType>(t));
        std::shared_ptr<const ProceduralClouds> lay;
        // The calibration's cache keeps one result per parameter set: the first build is
        // the one timed.
        const double t_build = median_s(1, [&] { lay = std::make_shared<const ProceduralClouds>(p); });
        SkyImageOptions o;
        o.clouds = lay;
        o.cloud_lighting.ray_spread_rad = a.spread;
        const std::clock_t c0 = std::clock();
        const double t_sky =
            median_s(a.repeats, [&] { render_equirect_sky(*type_lut, atm, obs, a.width, o); });
        // CPU time of all threads per repeat: on a loaded machine the wall time is not
        // the work.
        const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC / a.repeats;
        totals.push_back(
            {t_build + t_sky, t_build + cpu / double(tbb::info::default_concurrency()), double(t)});
        fmt::print("| {} | {:.2f} s | {:.2f} s | {:.2f} s | {:.2f} s |\n", kCloudTypeNames[t], t_build, t_sky,
                   t_build + t_sky, cpu);
        rows.push_back(fmt::format("type_sky,{},{}x{},{:.4f},,,,,,,", kCloudTypeNames[t], a.width,
                                   a.width / 2, t_build + t_sky));
        relit.push_back(relight_s(a, *type_lut, atm, obs, o));
        std::fflush(stdout);
    }
    // The same skies lit again (CloudViewCache): the sun turned, the clouds' view samples
    // kept from the render before (the add-on's live update after a lamp rotation).
    fmt::print("\n| type | sky again, the sun turned (samples kept) | kept samples |\n|---|---|---|\n");
    for (std::size_t k = 0; k < totals.size(); ++k)
        fmt::print("| {} | {:.2f} s | {:.0f} MB |\n", kCloudTypeNames[std::size_t(totals[k][2])], relit[k][0],
                   relit[k][1] / (1 << 20));
    // The types side by side against the target: a cloudy world in kTypeTargetS, the
    // layer's build included. The wall time on a shared machine is inflated by the other
    // load; the sky's CPU time over the threads (a perfect parallel efficiency) is what
    // idle cores would take, the layer's build added as timed.
    constexpr double kTypeTargetS = 2.0;
    std::string head = "\n| " + std::to_string(a.width) + "x" + std::to_string(a.width / 2) + ", over " +
                       fmt::format("{:.0f}", kTypeTargetS) + " s |",
                rule = "|---|", wall = "| wall time |", idle = "| build + sky's CPU time / threads |";
    for (const auto& [w, c, t] : totals) {
        head += fmt::format(" {} |", kCloudTypeNames[std::size_t(t)]);
        rule += "---|";
        wall += fmt::format(" {:.2f}x |", w / kTypeTargetS);
        idle += fmt::format(" {:.2f}x |", c / kTypeTargetS);
    }
    fmt::print("{}\n{}\n{}\n{}\n", head, rule, wall, idle);
}

// --- the cloudy sky --------------------------------------------------------------------
// One default layer (the cumulus preset, coverage 0.4), as `welkin sky --scene` renders
// it: every ray marched ("exact"), and the cloud pass upsampled (CloudUpsampling,
// lighting.hpp) at the default and at other settings. The error is taken against a
// converged march: the mean of `reference_seeds` exact images with other jitter seeds
// (the exact image's own jitter noise is its row): the mean over sky pixels of
// |difference| / the reference's mean, and the 99th percentile of the per-pixel
// relative difference.

// The converged march: the mean of exact images of jitter seeds 2 .. seeds + 1.
std::vector<double> converged_sky(const SkyMethod& lut, const Atmosphere& atm, const Observer& obs, int width,
                                  const std::shared_ptr<const ProceduralClouds>& layer, int seeds) {
    SkyImageOptions exact;
    exact.clouds = layer;
    exact.cloud_upsampling.stride = 1;
    std::vector<double> reference;
    for (int k = 0; k < seeds; ++k) {
        SkyImageOptions o = exact;
        o.cloud_lighting.seed = std::uint64_t(k + 2);
        const SkyImage img = render_equirect_sky(lut, atm, obs, width, o);
        if (reference.empty()) reference.assign(img.pixels.size(), 0.0);
        for (std::size_t q = 0; q < img.pixels.size(); ++q) reference[q] += img.pixels[q] / seeds;
    }
    return reference;
}

// An image's error against the converged sky over its upper half (the sky): the mean
// relative error and the 99th percentile of the per-pixel relative error.
std::array<double, 2> sky_error(const SkyImage& img, const std::vector<double>& reference) {
    double err = 0.0, ref = 0.0;
    std::vector<double> rel;
    const std::size_t npx = img.pixels.size() / 3;
    for (std::size_t q = 0; q < npx / 2; ++q) {  // the upper half: sky
        double d = 0.0, a = 0.0;
        for (int c = 0; c < 3; ++c) {
            d += std::abs(double(img.pixels[q * 3 + c]) - reference[q * 3 + c]);
            a += std::abs(reference[q * 3 + c]);
        }
        err += d;
        ref += a;
        rel.push_back(a > 0.0 ? d / a : 0.0);
    }
    std::nth_element(rel.begin(), rel.begin() + std::ptrdiff_t(rel.size() * 99 / 100), rel.end());
    const double p99 = rel[rel.size() * 99 / 100];
    const double mean_err = ref > 0.0 ? err / ref : 0.0;
    return {mean_err, p99};
}

// The upsampling's settings against the converged sky, one row each.
void bench_upsampling(const Args& a, const SkyMethod& lut, const Atmosphere& atm, const Observer& obs,
                      const std::shared_ptr<const ProceduralClouds>& layer, std::vector<std::string>& rows) {
    const std::vector<double> reference = converged_sky(lut, atm, obs, a.width, layer, a.reference_seeds);
    struct Setting {
        std::string name;
        CloudUpsampling up;
    };
    const auto setting = [](int stride, int finest, double dT, double dL, double block) {
        CloudUpsampling u;
        u.stride = stride, u.finest = finest, u.transmittance_tolerance = dT, u.radiance_tolerance = dL;
        u.max_block_size_m = block;
        return u;
    };
    const std::vector<Setting> settings{
        {"exact (every ray marched)", setting(1, 1, 0.0, 0.0, 0.0)},
        {"upsampled, the default (stride 0: a power of two near width / 256)", CloudUpsampling{}},
        {"upsampled, stride 4", setting(4, 2, 0.1, 0.3, 500.0)},
        {"upsampled, stride 16", setting(16, 2, 0.1, 0.3, 500.0)},
        {"upsampled, finest 1 (edges marched to the pixel)", setting(0, 1, 0.1, 0.3, 500.0)},
        {"upsampled, no block size limit", setting(0, 2, 0.1, 0.3, 1e7)},
        {"upsampled, tolerances dT 0.2 dL 0.6", setting(0, 2, 0.2, 0.6, 500.0)},
        {"upsampled, no refinement", setting(0, 16, 1.0, 1.0, 1e7)},
    };
    double t_exact = 0.0;
    for (const Setting& st : settings) {
        SkyImageOptions cloudy;
        cloudy.clouds = layer;
        cloudy.cloud_upsampling = st.up;
        SkyImage img;
        const double t =
            median_s(a.repeats, [&] { img = render_equirect_sky(lut, atm, obs, a.width, cloudy); });
        if (st.up.stride == 1) t_exact = t;
        const auto [mean_err, p99] = sky_error(img, reference);
        fmt::print(
            "| lut sky {}x{}, one {} layer, {} | {:.3f} s | {:.2f}x | {:.2f} % | {:.2f} % "
            "|\n",
            a.width, a.width / 2, a.upsampling_type.empty() ? "default cumulus" : a.upsampling_type, st.name,
            t, t_exact / t, 100.0 * mean_err, 100.0 * p99);
        rows.push_back(
            fmt::format("sky,{},cumulus_stride{}_finest{}_dT{}_dL{}_block{},{:.4f},,,,,,{:.5f},{:.5f}",
                        a.width, st.up.stride, st.up.finest, st.up.transmittance_tolerance,
                        st.up.radiance_tolerance, st.up.max_block_size_m, t, mean_err, p99));
        std::fflush(stdout);
    }
}

// The clear sky's time, the layer's bake and (unless --cases-only) the upsampling's
// settings; returns the layer, which the shadow grid's check reuses.
std::shared_ptr<const ProceduralClouds> bench_cloudy_sky(const Args& a, const Atmosphere& atm,
                                                         const Observer& obs,
                                                         std::vector<std::string>& rows) {
    CloudLayerParams params;  // the default layer, or --upsampling-type's preset
    for (std::size_t t = 0; t < kCloudTypeNames.size(); ++t)
        if (a.upsampling_type == kCloudTypeNames[t])
            params = CloudLayerParams::preset(static_cast<CloudType>(t));
    const auto t_bake0 = Clock::now();
    auto layer = std::make_shared<const ProceduralClouds>(params);
    const double bake = std::chrono::duration<double>(Clock::now() - t_bake0).count();
    const auto lut = make_sky_method("lut");
    SkyImageOptions clear;
    const double t_clear =
        a.cases_only ? 0.0
                     : median_s(a.repeats, [&] { render_equirect_sky(*lut, atm, obs, a.width, clear); });
    fmt::print("\n| what | time | speed-up over exact | mean error | p99 error |\n|---|---|---|---|---|\n");
    fmt::print("| noise bake and coverage calibration (once per layer) | {:.2f} s | | | |\n", bake);
    fmt::print("| lut sky {}x{}, clear | {:.3f} s | | | |\n", a.width, a.width / 2, t_clear);
    rows.push_back(fmt::format("sky,{},clear,{:.4f},,,,,", a.width, t_clear));
    if (!a.cases_only) bench_upsampling(a, *lut, atm, obs, layer, rows);
    return layer;
}

// --- fast vs reference -----------------------------------------------------------------
CloudLayerParams thin_layer_params() {
    CloudLayerParams thin;
    thin.bottom_altitude_m = 1500.0;
    thin.top_altitude_m = 2300.0;
    thin.coverage = 0.55;
    thin.cloud_type = CloudType::stratocumulus;
    thin.density_per_m = 0.004;
    thin.detail_strength = 0.6;
    return thin;
}

CloudLayerParams dense_layer_params() {
    CloudLayerParams dense;
    dense.bottom_altitude_m = 1500.0;
    dense.top_altitude_m = 2700.0;
    dense.coverage = 0.75;
    dense.density_per_m = 0.03;
    return dense;
}

// The VDB ball (write_ball_vdb), loaded and its file removed.
std::unique_ptr<const VdbClouds> ball_vdb_clouds() {
    const std::string vdb_path = write_ball_vdb();
    VdbCloudOptions vo;
    vo.matrix_world = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 1500.0, 900.0));
    vo.density_scale = 0.03;
    auto vdb = std::make_unique<const VdbClouds>(vdb_path, vo);
    std::filesystem::remove(vdb_path);
    return vdb;
}

struct Case {
    const char* name;
    const CloudDensity& density;
    glm::dvec3 centre;
    double half_angle;
    int paths;
};

// Quality settings of the fast march: (view steps, shadow steps), the optical-depth grid
// on; "legacy" is the march as it was before the grid, the dim-tail steps and the
// octaves' optical size (a shadow ray per sample, fixed steps), at the defaults' steps.
// "octaves" is the defaults with Wrenninge's octaves (weighted by the optical size) in
// place of the delta-Eddington slab (clouds/diffusion.hpp), as the default was before it.
struct MarchSetting {
    const char* label;
    int max_steps, light_steps;
    bool legacy, octaves;
};

const std::vector<MarchSetting> kMarchSettings = {
    {"24+4", 24, 4, false, false},           {"48+6", 48, 6, false, false},
    {"96+8 (default)", 96, 8, false, false}, {"192+16", 192, 16, false, false},
    {"512+32", 512, 32, false, false},       {"96+8 legacy", 96, 8, true, true},
    {"96+8 octaves", 96, 8, false, true}};

CloudLightingOptions options_of(const MarchSetting& st) {
    CloudLightingOptions o;
    o.max_steps = st.max_steps;
    o.light_steps = st.light_steps;
    o.ambient_steps = std::max(4, st.light_steps / 2);
    if (st.octaves) o.multiple_scattering = CloudMultipleScattering::octaves;
    if (st.legacy) {
        o.shadow_grid = false;
        o.tail_transmittance = 0.0;
        o.octave_optical_size = false;
    }
    return o;
}

// Error on the views against the reference (green channel): bias, mean absolute error,
// largest transmittance difference, and the reference's own standard error.
std::array<double, 4> case_errors(const std::vector<float>& L, const std::vector<float>& T,
                                  const CloudReferenceResult& ref, std::size_t nv) {
    double sf = 0, sr = 0, sa = 0, var = 0, dT = 0;
    for (std::size_t r = 0; r < nv; ++r) {
        sf += L[r * 3 + 1];
        sr += ref.radiance[r * 3 + 1];
        sa += std::abs(L[r * 3 + 1] - ref.radiance[r * 3 + 1]);
        var += double(ref.radiance_error[r * 3 + 1]) * ref.radiance_error[r * 3 + 1];
        dT = std::max(dT, std::abs(double(T[r]) - ref.transmittance[r]));
    }
    return std::array<double, 4>{sf / sr - 1.0, sa / sr, dT, std::sqrt(var) / sr};
}

// One case: the reference, the fast march at each setting, the reference at fewer paths
// (its noise for its time). Error on 6 x 6 views against the reference; time per million
// rays from a 128 x 128 grid of views in the same cone (the grid is shared by many rays,
// as in an image).
void bench_case(const Args& a, const Case& c, const CloudIllumination& light,
                const std::vector<MarchSetting>& settings, std::vector<std::string>& rows) {
    const auto dirs = view_grid(c.centre, c.half_angle, 6);
    const auto timing_dirs = view_grid(c.centre, c.half_angle, 128);
    CloudReferenceOptions ro;
    ro.paths = c.paths;
    CloudReferenceResult ref;
    const double t_ref = median_s(1, [&] {
        ref = render_clouds_reference(c.density, light, {0, 0, 0}, dirs, ro);
    });
    const double ref_se = case_errors(ref.radiance, ref.transmittance, ref, dirs.size())[3];
    for (const MarchSetting& st : settings) {
        const CloudLightingOptions opt = options_of(st);
        const CloudResult fast = render_clouds(c.density, light, {0, 0, 0}, dirs, opt);
        const double t_fast = median_s(a.repeats, [&] {
            render_clouds(c.density, light, {0, 0, 0}, timing_dirs, opt);
        });
        const auto e = case_errors(fast.radiance, fast.transmittance, ref, dirs.size());
        const double per_m = t_fast / double(timing_dirs.size()) * 1e6;
        fmt::print("| {} | fast {} | {:+.1f} % | {:.1f} % | {:.3f} | {:.2f} s |\n", c.name, st.label,
                   100 * e[0], 100 * e[1], e[2], per_m);
        rows.push_back(fmt::format("case,{},fast {},{:.5f},{:.5f},{:.5f},{:.5f},{:.4f},{}", c.name, st.label,
                                   per_m, e[0], e[1], e[2], t_ref, c.paths));
    }
    for (const int div : a.cases_only ? std::vector<int>{} : std::vector<int>{64, 16, 4}) {
        CloudReferenceOptions lo = ro;
        lo.paths = std::max(1, c.paths / div);
        lo.seed = ro.seed + 1000;  // independent of the full run
        CloudReferenceResult r2;
        const double t2 = median_s(1, [&] {
            r2 = render_clouds_reference(c.density, light, {0, 0, 0}, dirs, lo);
        });
        const auto e = case_errors(r2.radiance, r2.transmittance, ref, dirs.size());
        const double per_m = t2 / double(dirs.size()) * 1e6;
        fmt::print("| {} | reference {} paths | {:+.1f} % | {:.1f} % | {:.3f} | {:.0f} s |\n", c.name,
                   lo.paths, 100 * e[0], 100 * e[1], e[2], per_m);
        rows.push_back(fmt::format("reference,{},reference {} paths,{:.5f},{:.5f},{:.5f},{:.5f},{:.4f},{}",
                                   c.name, lo.paths, per_m, e[0], e[1], e[2], t_ref, c.paths));
    }
    fmt::print("| {} | reference {} paths (truth) | se {:.1f} % | | | {:.0f} s |\n", c.name, c.paths,
               100 * ref_se, t_ref / double(dirs.size()) * 1e6);
    rows.push_back(fmt::format("truth,{},reference {} paths,{:.5f},,{:.5f},,{:.4f},{}", c.name, c.paths,
                               t_ref / double(dirs.size()) * 1e6, ref_se, t_ref, c.paths));
}

void bench_fast_vs_reference(const Args& a, const std::vector<Case>& cases, std::vector<std::string>& rows) {
    const double e = 35.0 * kDegree;
    const ConstantIllumination light({std::cos(e), 0.0, std::sin(e)}, {1.0f, 1.0f, 1.0f},
                                     {0.04f, 0.04f, 0.04f});
    const std::vector<MarchSetting> settings =
        a.cases_only ? std::vector<MarchSetting>{kMarchSettings[2], kMarchSettings[6]} : kMarchSettings;
    fmt::print(
        "\n| case | method | bias | mean abs err | max dT | time per 1M rays |\n|---|---|---|---|---|---|\n");
    for (const Case& c : cases) bench_case(a, c, light, settings, rows);
    fmt::print("(errors on 36 views per case; sun 35 deg, constant sun and sky light; green channel)\n");
}

// --- a 1920 x 1080 camera view of the VDB ------------------------------------------------
void bench_vdb_view(const Args& a, const VdbClouds& vdb, const Atmosphere& atm, const Observer& obs,
                    std::vector<std::string>& rows) {
    const int cw = 1920, ch = 1080;
    const glm::dvec3 eye(0.0, 0.0, 0.0), target(0.0, 1500.0, 900.0);
    const glm::dvec3 fwd = glm::normalize(target - eye);
    const glm::dvec3 right = glm::normalize(glm::cross(fwd, glm::dvec3(0, 0, 1)));
    const glm::dvec3 up = glm::cross(right, fwd);
    const double tan_half = std::tan(0.5 * 20.0 * kDegree);  // 20 degrees across
    std::vector<glm::dvec3> cam(std::size_t(cw) * ch);
    for (int j = 0; j < ch; ++j)
        for (int i = 0; i < cw; ++i) {
            const double x = (2.0 * (i + 0.5) / cw - 1.0) * tan_half;
            const double y = (1.0 - 2.0 * (j + 0.5) / ch) * tan_half * ch / cw;
            cam[std::size_t(j) * cw + i] = glm::normalize(fwd + x * right + y * up);
        }
    const AtmosphereIllumination atm_light(atm, obs);
    fmt::print("\n| 1920x1080 camera view of the VDB (bruneton2017 light) | time |\n|---|---|\n");
    for (const MarchSetting& st : {kMarchSettings[2], kMarchSettings[5], kMarchSettings[6]}) {
        const CloudLightingOptions opt = options_of(st);
        // (legacy timed once: it is the slow one, and the point is the ratio)
        const double t =
            median_s(st.legacy ? 1 : a.repeats, [&] { render_clouds(vdb, atm_light, eye, cam, opt); });
        fmt::print("| fast {} | {:.3f} s |\n", st.label, t);
        rows.push_back(fmt::format("vdb_view,1920x1080,fast {},{:.4f},,,,,", st.label, t));
    }
}

// --- the optical-depth grid against a shadow ray per sample, on the sky's rays ------------
void bench_grid_check(const ProceduralClouds& layer, const Atmosphere& atm, const Observer& obs,
                      std::vector<std::string>& rows) {
    const int w = 512;
    std::vector<glm::dvec3> sky_dirs;
    for (int j = 0; j < w / 4; ++j)  // the upper hemisphere of a w x w/2 equirect
        for (int i = 0; i < w; ++i) {
            const double el = kPi / 2 * (1.0 - (j + 0.5) / (w / 4)), az = kTwoPi * (i + 0.5) / w;
            sky_dirs.push_back({std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)});
        }
    const AtmosphereIllumination atm_light(atm, obs);
    CloudLightingOptions with_grid, per_sample;
    per_sample.shadow_grid = false;
    const CloudResult a = render_clouds(layer, atm_light, {0, 0, 0}, sky_dirs, with_grid);
    const CloudResult b = render_clouds(layer, atm_light, {0, 0, 0}, sky_dirs, per_sample);
    double sa = 0, sb = 0, sd = 0;
    for (std::size_t i = 0; i < sky_dirs.size(); ++i) {
        sa += a.radiance[i * a.channels + 1];
        sb += b.radiance[i * b.channels + 1];
        sd += std::abs(a.radiance[i * a.channels + 1] - b.radiance[i * b.channels + 1]);
    }
    fmt::print(
        "\nshadow grid vs a shadow ray per sample, cumulus sky {}x{} upper half: mean {:+.2f} %, mean "
        "abs "
        "{:.2f} % of the mean radiance\n",
        w, w / 4, 100 * (sa / sb - 1), 100 * sd / sb);
    rows.push_back(fmt::format("grid_check,sky {}x{},grid vs per-sample,,{:.5f},{:.5f},,,", w, w / 4,
                               sa / sb - 1, sd / sb));
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Welkin cloud benchmark"};
    Args args;
    add_options(app, args);
    CLI11_PARSE(app, argc, argv);
    std::vector<std::string> rows;

    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const Observer obs{0.0, glm::normalize(glm::dvec3(0.6, 0.2, 0.5))};
    fmt::print("Welkin cloud benchmark: {} threads, {}x{} sky\n", tbb::info::default_concurrency(),
               args.width, args.width / 2);
    if (args.upsampling_type.empty() || args.types_only) bench_types(args, atm, obs, rows);
    if (args.types_only) return write_csv(args.csv, rows);
    const std::shared_ptr<const ProceduralClouds> layer = bench_cloudy_sky(args, atm, obs, rows);
    if (args.sky_only) return write_csv(args.csv, rows);

    const ProceduralClouds thin_layer(thin_layer_params()), dense_layer(dense_layer_params());
    const std::unique_ptr<const VdbClouds> vdb = ball_vdb_clouds();
    bench_fast_vs_reference(args,
                            {{"thin wispy", thin_layer, {0.3, 0.4, 1.0}, 0.5, 8192},
                             {"dense cumulus", dense_layer, {0.3, 0.4, 1.0}, 0.5, 512},
                             {"vdb", *vdb, {0.0, 1500.0, 900.0}, 0.12, 2048}},
                            rows);
    if (args.cases_only) return 0;
    bench_vdb_view(args, *vdb, atm, obs, rows);
    bench_grid_check(*layer, atm, obs, rows);
    return write_csv(args.csv, rows);
}
