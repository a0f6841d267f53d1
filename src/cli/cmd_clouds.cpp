// SPDX-License-Identifier: Apache-2.0
// `welkin clouds`: the scene camera's cloud passes (cloud_passes.hpp) from a scene JSON with
// "clouds", and optionally the render's depth (rays end at the geometry), as a multilayer
// OpenEXR with Welkin.Clouds (R, G, B, A) and Welkin.CloudDepth (Z).
#include <chrono>
#include <filesystem>
#include <memory>

#include "common.hpp"
#include "terminal_progress.hpp"
#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::cli {
namespace {

struct CloudsArgs : SceneOutputArgs {
    CloudsArgs() { output = "welkin_clouds.exr"; }
    std::string depth;
    std::string depth_channel;
};

int run_clouds(const CloudsArgs& args) {
    // Everything that can be refused is refused before the work starts.
    check_output_path(args.output, args.overwrite);
    const SceneDescription scene = load_camera_scene(args.scene);
    if (!scene.has_clouds())
        throw InvalidArgument("--scene", fmt::format("clouds: '{}' has no cloud layers or volumes (add a "
                                                     "\"clouds\" key: docs/pipelines.md \"Scene JSON\")",
                                                     args.scene));
    const int width = scene.resolution.width(), height = scene.resolution.height();
    DepthImage depth;
    if (!args.depth.empty())
        depth = load_depth(args.depth, args.depth_channel, scene);
    else if (!args.depth_channel.empty())
        throw InvalidArgument("--depth-channel", "needs --depth");
    const std::shared_ptr<const CloudDensity> clouds = load_scene_clouds(scene, args.scene);

    const auto threads = limit_threads(args.threads);
    install_interrupt_handler();
    const auto start = std::chrono::steady_clock::now();
    CloudPasses passes;
    {
        TerminalProgress progress(fmt::format("clouds {}x{}", width, height));
        passes = render_cloud_passes(scene, *clouds, depth.pixels, &progress);
        progress.finish();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (interrupted()) throw Cancelled();

    ExrImage exr;
    exr.width = width;
    exr.height = height;
    exr.channel_names = cloud_channel_names();
    const std::size_t n = std::size_t(width) * std::size_t(height);
    exr.pixels.resize(n * 5);
    std::size_t cloudy = 0;
    for (std::size_t p = 0; p < n; ++p) {
        for (int c = 0; c < 4; ++c) exr.pixels[p * 5 + c] = passes.clouds[p * 4 + c];
        exr.pixels[p * 5 + 4] = passes.depth[p];
        cloudy += passes.clouds[p * 4 + 3] > 0.0f;
    }
    ExrWriteOptions write = exr_write_options(args, scene);
    write.attributes.insert(write.attributes.end(),
                            {{"welkinUnits",
                              "Clouds: linear Rec.709, W m^-2 sr^-1 (times exposure), "
                              "premultiplied; CloudDepth: m (Blender's Z), 1e10 where no cloud"}});
    if (!args.depth.empty())
        write.attributes.push_back({"welkinDepth", fmt::format("{} ({})", args.depth, depth.channel)});
    write_exr(args.output, exr, write);
    fmt::print(
        "wrote {} ({} x {}, Welkin.Clouds and Welkin.CloudDepth, {}, {:.1f} % of pixels cloudy, "
        "{:.2f} s)\n",
        std::filesystem::absolute(args.output).string(), width, height, args.half ? "half" : "float",
        100.0 * double(cloudy) / double(n), seconds);
    return 0;
}

}  // namespace

Command add_clouds_command(CLI::App& app) {
    auto args = std::make_shared<CloudsArgs>();
    CLI::App* sub =
        app.add_subcommand("clouds",
                           "The scene camera's cloud passes (Welkin.Clouds, Welkin.CloudDepth) from a scene "
                           "JSON with \"clouds\", as a multilayer OpenEXR");
    add_scene_output_options(
        sub, *args, "Scene description JSON with a camera and \"clouds\" (docs/pipelines.md \"Scene JSON\")");
    sub->add_option("--depth", args->depth,
                    "OpenEXR holding the render's depth (Blender's Z pass); rays end at the "
                    "geometry, so that it hides the clouds behind it (default: no geometry)")
        ->type_name("FILE.exr");
    sub->add_option("--depth-channel", args->depth_channel,
                    "Channel of --depth to read (default: Z, Depth.Z, or the one <layer>.Depth.Z)")
        ->type_name("NAME");
    sub->footer(
        "Channels: Welkin.Clouds.{R,G,B,A} (premultiplied; linear Rec.709, W m^-2 sr^-1, times the "
        "scene's exposure; the air between the camera and the cloud included) and "
        "Welkin.CloudDepth.Z (metres, Blender's Z convention; 1e10 where no cloud). Composite: "
        "final = Clouds + (1 - Clouds.A) x (Image x AerialTransmittance + AerialInscatter). A "
        "missing or unreadable VDB is refused naming clouds.volumes[i].file; nothing is written. "
        "Ctrl-C cancels cleanly.");
    return {sub, [args] { return run_clouds(*args); }};
}

}  // namespace welkin::cli
