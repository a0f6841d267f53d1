// SPDX-License-Identifier: Apache-2.0
// `welkin aerial`: aerial-perspective passes for a rendered frame, from its scene
// description and its depth (Blender's Z pass), as a multilayer OpenEXR with the layers
// Welkin.AerialInscatter and Welkin.AerialTransmittance (R, G, B each).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "common.hpp"
#include "terminal_progress.hpp"
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/memory.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::cli {
namespace {

struct AerialArgs : SceneOutputArgs {
    AerialArgs() { output = "welkin_aerial.exr"; }
    std::string depth;
    std::string depth_channel;
    std::string method;  // empty: the scene's
};

// Re-raises an InvalidArgument from the core under the option it came through, keeping
// the core's parameter in the message: "--scene: camera.lens_mm: must be ...".
[[noreturn]] void rethrow_as(const std::string& option, const InvalidArgument& e,
                             const std::string& where = "") {
    throw InvalidArgument(
        option, where.empty() ? std::string(e.what()) : fmt::format("{} (in '{}')", e.what(), where));
}

int run_aerial(const AerialArgs& args) {
    // Everything that can be refused is refused before the work starts.
    check_output_path(args.output, args.overwrite);
    SceneDescription scene = load_camera_scene(args.scene);
    if (!args.method.empty()) scene.aerial.method = aerial_method_from_name(args.method, "--method");
    const int width = scene.resolution.width(), height = scene.resolution.height();
    try {
        // Besides the core's buffers: the EXR image (6 floats a pixel), and its half copy.
        check_frame_memory(width, height,
                           kAerialPassBytesPerPixel + 6 * sizeof(float) + (args.half ? 6 * 2 : 0),
                           "depth, aerial passes and EXR image");
    } catch (const InvalidArgument& e) {
        rethrow_as("--scene", e, args.scene);
    }

    const DepthImage depth_image = load_depth(args.depth, args.depth_channel, scene);
    const std::vector<float>& depth = depth_image.pixels;
    const std::string& channel = depth_image.channel;
    // The scene's clouds (their VDBs opened now: a bad one is refused before any work).
    const std::shared_ptr<const CloudDensity> clouds = load_scene_clouds(scene, args.scene);

    const auto threads = limit_threads(args.threads);

    install_interrupt_handler();
    const auto start = std::chrono::steady_clock::now();
    AerialPasses passes;
    {
        TerminalProgress progress(
            fmt::format("aerial {}x{} ({})", width, height, aerial_method_name(scene.aerial.method)));
        passes = aerial_perspective(scene.aerial_view(), depth, width, height, &progress);
        progress.finish();
    }
    if (interrupted()) throw Cancelled();
    // With clouds: Welkin.Clouds and Welkin.CloudDepth, marched up to the render's depth.
    CloudPasses cloud_passes;
    if (clouds) {
        TerminalProgress progress(fmt::format("clouds {}x{}", width, height));
        cloud_passes = render_cloud_passes(scene, *clouds, depth, &progress);
        progress.finish();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (interrupted()) throw Cancelled();

    ExrImage exr;
    exr.width = width;
    exr.height = height;
    exr.channel_names = {"Welkin.AerialInscatter.R",     "Welkin.AerialInscatter.G",
                         "Welkin.AerialInscatter.B",     "Welkin.AerialTransmittance.R",
                         "Welkin.AerialTransmittance.G", "Welkin.AerialTransmittance.B"};
    if (clouds)
        for (const std::string& c : cloud_channel_names()) exr.channel_names.push_back(c);
    const std::size_t n = std::size_t(width) * std::size_t(height), nch = exr.channel_names.size();
    exr.pixels.resize(n * nch);
    for (std::size_t p = 0; p < n; ++p) {
        for (int c = 0; c < 3; ++c) {
            exr.pixels[p * nch + c] = passes.inscatter[p * 3 + c];
            exr.pixels[p * nch + 3 + c] = passes.transmittance[p * 3 + c];
        }
        if (clouds) {
            for (int c = 0; c < 4; ++c) exr.pixels[p * nch + 6 + c] = cloud_passes.clouds[p * 4 + c];
            exr.pixels[p * nch + 10] = cloud_passes.depth[p];
        }
    }
    passes = {};
    cloud_passes = {};
    ExrWriteOptions write = exr_write_options(args, scene);
    write.attributes.insert(write.attributes.end(),
                            {{"welkinDepth", fmt::format("{} ({})", args.depth, channel)},
                             {"welkinUnits",
                              "AerialInscatter, Clouds: linear Rec.709, W m^-2 sr^-1 (times "
                              "exposure); AerialTransmittance: dimensionless; CloudDepth: m"}});
    write_exr(args.output, exr, write);
    fmt::print(
        "wrote {} ({} x {}, Welkin.AerialInscatter and Welkin.AerialTransmittance{}, {}, "
        "method {}, {:.2f} s)\n",
        std::filesystem::absolute(args.output).string(), width, height,
        clouds ? ", Welkin.Clouds and Welkin.CloudDepth" : "", args.half ? "half" : "float",
        aerial_method_name(scene.aerial.method), seconds);
    return 0;
}

}  // namespace

Command add_aerial_command(CLI::App& app) {
    auto args = std::make_shared<AerialArgs>();
    CLI::App* sub =
        app.add_subcommand("aerial",
                           "Aerial-perspective passes (in-scattering and transmittance) for a rendered "
                           "frame, from its scene JSON and its depth (Z pass), as a multilayer OpenEXR");
    add_scene_output_options(
        sub, *args,
        "Scene description JSON (the schema the Blender add-on writes; see docs/pipelines.md "
        "\"Scene JSON\"): atmosphere, sun, camera, render resolution");
    sub->add_option("--depth", args->depth,
                    "OpenEXR holding the frame's depth: Blender's Z pass, metres along the "
                    "view axis (along the ray for panoramic cameras); +inf or >= 1e9 m is sky")
        ->type_name("FILE.exr")
        ->required();
    sub->add_option("--depth-channel", args->depth_channel,
                    "Channel of --depth to read (default: Z, Depth.Z, or the one "
                    "<layer>.Depth.Z of a Blender multilayer EXR)")
        ->type_name("NAME");
    sub->add_option("--method", args->method,
                    "froxel (Hillaire 2020's camera volume, fast) or raymarch (every pixel "
                    "marched); default: the scene's aerial.method")
        ->type_name("NAME")
        ->check(CLI::IsMember({"froxel", "raymarch"}));
    sub->footer(
        "Layers: Welkin.AerialInscatter (R, G, B: linear Rec.709, W m^-2 sr^-1, times the "
        "scene's exposure) and Welkin.AerialTransmittance (R, G, B), so that Image x "
        "Transmittance + Inscatter is the hazed render. With \"clouds\" in the scene also "
        "Welkin.Clouds (R, G, B, A: premultiplied, the air in front included) and "
        "Welkin.CloudDepth (Z; 1e10 where no cloud): final = Clouds + (1 - Clouds.A) x hazed. Sky pixels get "
        "transmittance 1 and "
        "no in-scattering (the rendered sky already holds the atmosphere). Rows top first, "
        "as EXR files are. Ctrl-C cancels cleanly; nothing is written.");
    return {sub, [args] { return run_aerial(*args); }};
}

}  // namespace welkin::cli
