// SPDX-License-Identifier: Apache-2.0
#include "common.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <thread>

#include "terminal_progress.hpp"
#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/aerosol.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/base/memory.hpp"
#include "welkin/io/file.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::cli {

void add_atmosphere_options(CLI::App* app, AtmosphereArgs& args) {
    auto* preset = app->add_option("--preset", args.preset,
                                   fmt::format("Built-in atmosphere: {} (see `welkin presets`)",
                                               fmt::join(Atmosphere::preset_names(), ", ")))
                       ->type_name("NAME")
                       ->capture_default_str();
    auto* file = app->add_option("--atmosphere", args.file,
                                 "Atmosphere from a JSON file (the schema `welkin atmosphere` "
                                 "writes); replaces --preset")
                     ->type_name("FILE.json");
    file->excludes(preset);
    app->add_flag("--spectral", args.spectral,
                  "Compute at 48 wavelengths (360-830 nm, 10 nm apart) and convert through "
                  "the CIE 1931 functions, instead of 4 (620, 560, 480, 440 nm) and a "
                  "conversion fitted to the 48-wavelength path; about 12x slower. With --preset only");
    auto* aod = app->add_option("--aerosol-optical-depth", args.aerosol_optical_depth,
                                "Vertical aerosol optical depth at 550 nm, in [0, 10]: scales the "
                                "atmosphere's aerosol to it (0.05 very clear, 0.12 a clear day, "
                                "0.3 hazy, 0.6 polluted); default: the preset's (`welkin presets`)")
                    ->type_name("TAU")
                    ->check(CLI::Range(0.0, 10.0));
    app->add_option("--turbidity", args.turbidity,
                    "Preetham's turbidity T in [1, 20] instead of --aerosol-optical-depth: "
                    "tau_550 = (0.04608 T - 0.04586) 0.55^-1.3 (T 2: 0.10, T 3: 0.20)")
        ->type_name("T")
        ->check(CLI::Range(1.0, 20.0))
        ->excludes(aod);
}

namespace {

// The atmosphere with the aerosol optical depth the options ask for, if any.
Atmosphere with_aerosol(Atmosphere atm, const AtmosphereArgs& args) {
    if (args.turbidity >= 0.0)
        set_aerosol_optical_depth(atm, preetham_turbidity_to_aerosol_optical_depth(args.turbidity));
    else if (args.aerosol_optical_depth >= 0.0)
        try {
            set_aerosol_optical_depth(atm, args.aerosol_optical_depth);
        } catch (const InvalidArgument& e) {
            throw InvalidArgument("--aerosol-optical-depth", e.what());
        }
    return atm;
}

}  // namespace

Atmosphere load_atmosphere(const AtmosphereArgs& args) {
    if (!args.file.empty()) {
        if (args.spectral)
            throw InvalidArgument("--spectral",
                                  "applies to --preset only: a JSON atmosphere sets its own "
                                  "\"wavelengths_nm\" (with \"preset\" it resamples that "
                                  "preset)");
        try {
            return with_aerosol(Atmosphere::from_json_file(args.file), args);
        } catch (const IoError& e) {
            throw InvalidArgument("--atmosphere", e.what());
        } catch (const InvalidArgument& e) {
            // The core may name the parameter twice ("p: p: message"): say it once.
            std::string what = e.what();
            const std::string twice = e.parameter() + ": " + e.parameter() + ": ";
            if (what.rfind(twice, 0) == 0) what = what.substr(e.parameter().size() + 2);
            throw InvalidArgument("--atmosphere", what);
        }
    }
    try {
        return with_aerosol(args.spectral ? Atmosphere::preset(args.preset, spectral_wavelengths_nm())
                                          : Atmosphere::preset(args.preset),
                            args);
    } catch (const InvalidArgument& e) {
        // "preset: unknown preset 'x'; choose one of: ..." -> named after the option.
        const std::string what = e.what();
        const std::string prefix = e.parameter() + ": ";
        throw InvalidArgument("--preset", what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
    }
}

void add_observer_options(CLI::App* app, ObserverArgs& args) {
    app->add_option("--sun-elevation", args.sun_elevation_deg,
                    "Sun elevation above the horizontal (XY) plane, degrees in [-90, 90]")
        ->type_name("DEG")
        ->check(CLI::Range(-90.0, 90.0))
        ->capture_default_str();
    app->add_option("--sun-azimuth", args.sun_azimuth_deg,
                    "Sun azimuth, degrees counter-clockwise from +X (0: +X, the centre of "
                    "the image; 90: +Y), in [-360, 360]")
        ->type_name("DEG")
        ->check(CLI::Range(-360.0, 360.0))
        ->capture_default_str();
    app->add_option("--altitude", args.altitude_m,
                    "Observer altitude above the ground, metres in [0, 1e9] (above the top "
                    "of the atmosphere is allowed)")
        ->type_name("M")
        ->check(CLI::Range(0.0, 1e9))
        ->capture_default_str();
}

Observer make_observer(const ObserverArgs& args) {
    // CLI::Range lets NaN through (every comparison with NaN is false).
    require_in_range("--sun-elevation", args.sun_elevation_deg, -90.0, 90.0, "degrees");
    require_in_range("--sun-azimuth", args.sun_azimuth_deg, -360.0, 360.0, "degrees");
    require_in_range("--altitude", args.altitude_m, 0.0, 1e9, "m");
    const double e = args.sun_elevation_deg * kDegree, a = args.sun_azimuth_deg * kDegree;
    Observer o;
    o.altitude_m = args.altitude_m;
    o.sun_direction = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
    return o.validated();
}

void check_output_path(const std::string& path, bool overwrite) {
    namespace fs = std::filesystem;
    if (path.empty()) throw InvalidArgument("--output", "must not be empty");
    // Symlinks followed; a directory, device, FIFO or socket refused (even with --overwrite).
    fs::path target;
    try {
        target = resolve_output_path(path, overwrite);
    } catch (const NotRegularFile& e) {
        throw InvalidArgument("--output", e.what());
    } catch (const IoError& e) {
        std::string what = e.what();
        const std::string tail = "(pass overwrite)";
        if (what.size() > tail.size() && what.compare(what.size() - tail.size(), tail.size(), tail) == 0)
            what = what.substr(0, what.size() - tail.size()) + "(pass --overwrite to replace it)";
        throw IoError(what);
    }
    const fs::path dir = target.parent_path();
    // access() says yes to root everywhere: create (and remove) a probe file instead.
    std::error_code ec;
    const fs::path probe = dir / fmt::format(".welkin-probe-{}", static_cast<long>(::getpid()));
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (fd < 0)
        throw IoError(fmt::format("cannot write '{}': directory '{}' is not writable ({})", path,
                                  dir.string(), std::strerror(errno)));
    ::close(fd);
    fs::remove(probe, ec);
}

SceneDescription load_camera_scene(const std::string& path) {
    try {
        SceneDescription scene = SceneDescription::from_json_file(path);
        scene.require_camera();
        return scene;
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("--scene", fmt::format("{} (in '{}')", e.what(), path));
    } catch (const IoError& e) {
        throw InvalidArgument("--scene", e.what());
    }
}

// The depth channel: --depth-channel, else "Z" (a plain EXR with Blender's Z buffer),
// "Depth.Z", or the one "<view layer>.Depth.Z" of a multilayer render.
static std::string find_depth_channel(const std::vector<std::string>& names, const std::string& asked,
                                      const std::string& path) {
    const auto has = [&](const std::string& n) {
        return std::find(names.begin(), names.end(), n) != names.end();
    };
    const std::string listed = fmt::format("{}", fmt::join(names, ", "));
    if (!asked.empty()) {
        if (has(asked)) return asked;
        throw InvalidArgument("--depth-channel",
                              fmt::format("'{}' has no channel '{}'; its channels: {}", path, asked, listed));
    }
    for (const char* n : {"Z", "Depth.Z"})
        if (has(n)) return n;
    std::vector<std::string> layered;
    for (const std::string& n : names)
        if (n.size() > 8 && n.compare(n.size() - 8, 8, ".Depth.Z") == 0) layered.push_back(n);
    if (layered.size() == 1) return layered.front();
    if (layered.size() > 1)
        throw InvalidArgument("--depth-channel", fmt::format("'{}' has several depth channels ({}); name one",
                                                             path, fmt::join(layered, ", ")));
    throw InvalidArgument("--depth-channel",
                          fmt::format("'{}' has no depth channel (looked for Z, Depth.Z and "
                                      "<layer>.Depth.Z; its channels: {}); enable the Z pass "
                                      "in Blender's View Layer properties, or name the channel",
                                      path, listed));
}

DepthImage load_depth(const std::string& path, const std::string& asked_channel,
                      const SceneDescription& scene) {
    const int width = scene.resolution.width(), height = scene.resolution.height();
    ExrHeaderInfo header;
    try {
        header = read_exr_header(path);
    } catch (const IoError& e) {
        throw InvalidArgument("--depth", e.what());
    }
    DepthImage out;
    out.channel = find_depth_channel(header.channel_names, asked_channel, path);
    if (header.width != width || header.height != height)
        throw InvalidArgument(
            "--depth", fmt::format("'{}' is {} x {} pixels but the scene renders {} x {} "
                                   "(resolution {} x {} at {} %)",
                                   path, header.width, header.height, width, height, scene.resolution.x,
                                   scene.resolution.y, scene.resolution.percentage));
    ExrImage depth;
    try {
        depth = read_exr_channels(path, {out.channel});
    } catch (const IoError& e) {
        throw InvalidArgument("--depth", e.what());
    }
    try {
        validate_depth(depth.pixels, width, height);
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("--depth", fmt::format("channel '{}' of '{}': {}", out.channel, path,
                                                     std::string(e.what()).substr(e.parameter().size() + 2)));
    }
    out.pixels = std::move(depth.pixels);
    return out;
}

std::shared_ptr<const CloudDensity> load_scene_clouds(const SceneDescription& scene,
                                                      const std::string& scene_path) {
    try {
        const auto clouds = scene.cloud_density();
        // Besides the passes: the cloud march's buffers and the EXR's 5 cloud channels.
        if (clouds)
            check_frame_memory(scene.resolution.width(), scene.resolution.height(),
                               kAerialPassBytesPerPixel + 96 + 48 + 20, "aerial and cloud passes");
        return clouds;
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("--scene", fmt::format("{} (in '{}')", e.what(), scene_path));
    }
}

std::vector<std::string> cloud_channel_names() {
    return {"Welkin.Clouds.R", "Welkin.Clouds.G", "Welkin.Clouds.B", "Welkin.Clouds.A",
            "Welkin.CloudDepth.Z"};
}

std::unique_ptr<tbb::global_control> limit_threads(int threads) {
    // ZIP compression of a 2048 x 1024 float image takes ~0.4 s on one thread.
    set_exr_thread_count(threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency())));
    if (threads <= 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 std::size_t(threads));
}

ExrWriteOptions exr_write_options(bool overwrite, bool half) {
    ExrWriteOptions write;
    write.overwrite = overwrite;
    write.pixel_type = half ? ExrPixelType::Half : ExrPixelType::Float;
    write.attributes = {{"software", fmt::format("welkin {}", kVersion)}};
    write.cancelled = [] { return interrupted(); };  // Ctrl-C during the write
    return write;
}

void add_scene_output_options(CLI::App* app, SceneOutputArgs& args, const std::string& scene_help) {
    app->add_option("--scene", args.scene, scene_help)->type_name("FILE.json")->required();
    app->add_flag("--half", args.half, "Write 16-bit half floats (default: 32-bit float)");
    app->add_flag("--overwrite", args.overwrite, "Replace the output file if it exists");
    app->add_option("-o,--output", args.output, "Output multilayer EXR; never replaced unless --overwrite")
        ->type_name("FILE.exr")
        ->capture_default_str();
    app->add_option("--threads", args.threads, "Worker threads, in [1, 1024] (default: all cores)")
        ->type_name("N")
        ->check(CLI::Range(1, 1024));
}

ExrWriteOptions exr_write_options(const SceneOutputArgs& args, const SceneDescription& scene) {
    ExrWriteOptions write = exr_write_options(args.overwrite, args.half);
    write.attributes.push_back({"welkinScene", nlohmann::json::parse(scene.to_json_string()).dump()});
    return write;
}

void add_color_space_option(CLI::App* app, std::string& value) {
    app->add_option("--color-space", value,
                    "Linear RGB space of the colours written: rec709 (sRGB primaries, D65), "
                    "rec2020 (ITU-R BT.2020, D65) or acescg (ACES AP1, ACES white by the Bradford "
                    "adaptation); each from the spectrum's CIE XYZ through the space's matrix")
        ->check(CLI::IsMember({"rec709", "rec2020", "acescg"}));
}

}  // namespace welkin::cli
