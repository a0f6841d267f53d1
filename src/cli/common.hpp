// SPDX-License-Identifier: Apache-2.0
// Pieces the `welkin` subcommands share: choosing an atmosphere, placing the sun, checking
// an output path before any work, and the command registry.
//
// The CLI owns no physics (docs/design.md): every number comes from the core. Angles
// are degrees here, at the user's edge, and radians from here on.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/scene/scene.hpp"
#include "welkin/sky/method.hpp"

namespace welkin::cli {

inline constexpr const char* kVersion = "0.1.0";  // keep in step with CMakeLists.txt

// A registered subcommand and what runs it once the command line is parsed.
struct Command {
    CLI::App* app = nullptr;
    std::function<int()> run;
};

Command add_sky_command(CLI::App& app);
Command add_sun_command(CLI::App& app);
Command add_presets_command(CLI::App& app);
Command add_atmosphere_command(CLI::App& app);
Command add_exr_info_command(CLI::App& app);
Command add_aerial_command(CLI::App& app);
Command add_plate_command(CLI::App& app);
Command add_clouds_command(CLI::App& app);

// --preset NAME | --atmosphere FILE.json, --spectral, and the aerosol's optical depth
// (--aerosol-optical-depth TAU | --turbidity T; negative: the atmosphere's own).
struct AtmosphereArgs {
    std::string preset = kDefaultPreset;
    std::string file;
    bool spectral = false;
    double aerosol_optical_depth = -1.0;
    double turbidity = -1.0;
};
void add_atmosphere_options(CLI::App* app, AtmosphereArgs& args);
// Throws InvalidArgument naming --preset, --atmosphere, --spectral, --aerosol-optical-depth
// or --turbidity.
Atmosphere load_atmosphere(const AtmosphereArgs& args);

// --sun-elevation DEG, --sun-azimuth DEG, --altitude M.
struct ObserverArgs {
    double sun_elevation_deg = 30.0;
    double sun_azimuth_deg = 0.0;
    double altitude_m = 0.0;
};
void add_observer_options(CLI::App* app, ObserverArgs& args);

// --color-space rec709|rec2020|acescg: the linear RGB of every colour the command writes
// (color_space.hpp); `value` keeps its default when the option is not given.
void add_color_space_option(CLI::App* app, std::string& value);
// Unit vector towards the sun: azimuth counter-clockwise from +X, elevation above XY.
Observer make_observer(const ObserverArgs& args);

// The scene JSON of --scene, with a camera (for the commands that render through it).
// Throws InvalidArgument naming --scene: the core's message and the file, or the read error.
SceneDescription load_camera_scene(const std::string& path);

// --depth FILE.exr (and --depth-channel NAME, empty: Z, Depth.Z or the one <layer>.Depth.Z):
// the Z pass at the scene's resolution, validated. InvalidArgument naming --depth or
// --depth-channel.
struct DepthImage {
    std::vector<float> pixels;  // (height, width), top row first
    std::string channel;        // the channel read
};
DepthImage load_depth(const std::string& path, const std::string& channel, const SceneDescription& scene);

// The scene's clouds (scene.cloud_density(): the VDB files are opened here, before any
// work), or nullptr without clouds. InvalidArgument naming --scene with the core's key
// ("clouds.volumes[0].file: ...") and the scene file.
std::shared_ptr<const CloudDensity> load_scene_clouds(const SceneDescription& scene,
                                                      const std::string& scene_path);

// The EXR channels of the cloud passes: Welkin.Clouds.{R,G,B,A}, Welkin.CloudDepth.Z (the
// add-on's pass channels).
std::vector<std::string> cloud_channel_names();

// Before any long work: refuse an existing file (unless overwrite) and a directory that
// does not exist or cannot be written. Throws IoError naming the path.
void check_output_path(const std::string& path, bool overwrite);

// --threads N (0: all cores): caps TBB's workers while the returned object lives (null when
// uncapped) and gives OpenEXR's compression as many threads.
std::unique_ptr<tbb::global_control> limit_threads(int threads);

// How an output EXR is written: --overwrite, --half (else 32-bit float), and the
// "software" provenance attribute; commands append their own attributes.
ExrWriteOptions exr_write_options(bool overwrite, bool half);

// The commands that render a scene's camera to a multilayer EXR (aerial, clouds, plate)
// take their scene and write their file alike: --scene FILE.json (required; `scene_help`
// says what the command needs of it), -o/--output (default `output`, never replaced unless
// --overwrite), --half, --overwrite and --threads N.
struct SceneOutputArgs {
    std::string scene;
    std::string output;
    bool half = false;
    bool overwrite = false;
    int threads = 0;
};
void add_scene_output_options(CLI::App* app, SceneOutputArgs& args, const std::string& scene_help);
// exr_write_options(args.overwrite, args.half) plus the "welkinScene" attribute: the scene
// description the passes were made from (compact JSON), so a file reproduces its frame.
ExrWriteOptions exr_write_options(const SceneOutputArgs& args, const SceneDescription& scene);

}  // namespace welkin::cli
