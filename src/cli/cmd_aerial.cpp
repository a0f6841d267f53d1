// `welkin aerial`: aerial-perspective passes for a rendered frame, from its scene
// description and its depth (Blender's Z pass), as a multilayer OpenEXR with the layers
// Welkin.AerialInscatter and Welkin.AerialTransmittance (R, G, B each).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "common.hpp"
#include "terminal_progress.hpp"
#include "welkin/aerial_perspective.hpp"
#include "welkin/error.hpp"
#include "welkin/exr_io.hpp"
#include "welkin/scene.hpp"

namespace welkin::cli {
namespace {

struct AerialArgs {
    std::string scene;
    std::string depth;
    std::string depth_channel;
    std::string method;  // empty: the scene's
    std::string output = "welkin_aerial.exr";
    bool half = false;
    bool overwrite = false;
    int threads = 0;
};

// Re-raises an InvalidArgument from the core under the option it came through, keeping
// the core's parameter in the message: "--scene: camera.lens_mm: must be ...".
[[noreturn]] void rethrow_as(const std::string& option, const InvalidArgument& e,
                             const std::string& where = "") {
    throw InvalidArgument(option, where.empty() ? std::string(e.what())
                                                : fmt::format("{} (in '{}')", e.what(), where));
}

// The depth channel: --depth-channel, else "Z" (a plain EXR with Blender's Z buffer),
// "Depth.Z", or the one "<view layer>.Depth.Z" of a multilayer render.
std::string find_depth_channel(const std::vector<std::string>& names, const std::string& asked,
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
        throw InvalidArgument("--depth-channel",
                              fmt::format("'{}' has several depth channels ({}); name one",
                                          path, fmt::join(layered, ", ")));
    throw InvalidArgument("--depth-channel",
                          fmt::format("'{}' has no depth channel (looked for Z, Depth.Z and "
                                      "<layer>.Depth.Z; its channels: {}); enable the Z pass "
                                      "in Blender's View Layer properties, or name the channel",
                                      path, listed));
}

int run_aerial(const AerialArgs& args) {
    // Everything that can be refused is refused before the work starts.
    check_output_path(args.output, args.overwrite);
    SceneDescription scene = load_camera_scene(args.scene);
    if (!args.method.empty()) scene.aerial.method = aerial_method_from_name(args.method, "--method");
    const int width = scene.resolution.width(), height = scene.resolution.height();
    try {
        // Besides the core's buffers: the EXR image (6 floats a pixel), and its half copy.
        check_aerial_memory(width, height, 6 * sizeof(float) + (args.half ? 6 * 2 : 0));
    } catch (const InvalidArgument& e) {
        rethrow_as("--scene", e, args.scene);
    }

    ExrHeaderInfo header;
    try {
        header = read_exr_header(args.depth);
    } catch (const IoError& e) {
        throw InvalidArgument("--depth", e.what());
    }
    const std::string channel = find_depth_channel(header.channel_names, args.depth_channel, args.depth);
    if (header.width != width || header.height != height)
        throw InvalidArgument("--depth",
                              fmt::format("'{}' is {} x {} pixels but the scene renders {} x {} "
                                          "(resolution {} x {} at {} %)",
                                          args.depth, header.width, header.height, width, height,
                                          scene.resolution.x, scene.resolution.y,
                                          scene.resolution.percentage));
    ExrImage depth;
    try {
        depth = read_exr_channels(args.depth, {channel});
    } catch (const IoError& e) {
        throw InvalidArgument("--depth", e.what());
    }
    try {
        validate_depth(depth.pixels, width, height);
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("--depth", fmt::format("channel '{}' of '{}': {}", channel, args.depth,
                                                     std::string(e.what()).substr(e.parameter().size() + 2)));
    }

    const auto threads = limit_threads(args.threads);

    install_interrupt_handler();
    const auto start = std::chrono::steady_clock::now();
    AerialPasses passes;
    {
        TerminalProgress progress(fmt::format("aerial {}x{} ({})", width, height,
                                              aerial_method_name(scene.aerial.method)));
        passes = aerial_perspective(scene, depth.pixels, width, height, &progress);
        progress.finish();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (interrupted()) throw Cancelled();
    depth = {};

    ExrImage exr;
    exr.width = width;
    exr.height = height;
    exr.channel_names = {"Welkin.AerialInscatter.R",    "Welkin.AerialInscatter.G",
                         "Welkin.AerialInscatter.B",    "Welkin.AerialTransmittance.R",
                         "Welkin.AerialTransmittance.G", "Welkin.AerialTransmittance.B"};
    const std::size_t n = std::size_t(width) * std::size_t(height);
    exr.pixels.resize(n * 6);
    for (std::size_t p = 0; p < n; ++p)
        for (int c = 0; c < 3; ++c) {
            exr.pixels[p * 6 + c] = passes.inscatter[p * 3 + c];
            exr.pixels[p * 6 + 3 + c] = passes.transmittance[p * 3 + c];
        }
    passes = {};
    ExrWriteOptions write = exr_write_options(args.overwrite, args.half);
    write.attributes.insert(write.attributes.end(),
                            {{"welkinDepth", fmt::format("{} ({})", args.depth, channel)},
                        {"welkinScene", nlohmann::json::parse(scene.to_json_string()).dump()},
                        {"welkinUnits", "AerialInscatter: linear Rec.709, W m^-2 sr^-1 (times "
                                        "exposure); AerialTransmittance: dimensionless"}});
    write_exr(args.output, exr, write);
    fmt::print("wrote {} ({} x {}, Welkin.AerialInscatter and Welkin.AerialTransmittance, {}, "
               "method {}, {:.2f} s)\n",
               std::filesystem::absolute(args.output).string(), width, height,
               args.half ? "half" : "float", aerial_method_name(scene.aerial.method), seconds);
    return 0;
}

}  // namespace

Command add_aerial_command(CLI::App& app) {
    auto args = std::make_shared<AerialArgs>();
    CLI::App* sub = app.add_subcommand(
        "aerial", "Aerial-perspective passes (in-scattering and transmittance) for a rendered "
                  "frame, from its scene JSON and its depth (Z pass), as a multilayer OpenEXR");
    sub->add_option("--scene", args->scene,
                    "Scene description JSON (the schema the Blender add-on writes; see README "
                    "\"Scene JSON\"): atmosphere, sun, camera, render resolution")
        ->type_name("FILE.json")
        ->required();
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
    sub->add_flag("--half", args->half, "Write 16-bit half floats (default: 32-bit float)");
    sub->add_flag("--overwrite", args->overwrite, "Replace the output file if it exists");
    sub->add_option("-o,--output", args->output,
                    "Output multilayer EXR; never replaced unless --overwrite")
        ->type_name("FILE.exr")
        ->capture_default_str();
    sub->add_option("--threads", args->threads, "Worker threads, in [1, 1024] (default: all cores)")
        ->type_name("N")
        ->check(CLI::Range(1, 1024));
    sub->footer(
        "Layers: Welkin.AerialInscatter (R, G, B: linear Rec.709, W m^-2 sr^-1, times the "
        "scene's exposure) and Welkin.AerialTransmittance (R, G, B), so that Image x "
        "Transmittance + Inscatter is the hazed render. Sky pixels get transmittance 1 and "
        "no in-scattering (the rendered sky already holds the atmosphere). Rows top first, "
        "as EXR files are. Ctrl-C cancels cleanly; nothing is written.");
    return {sub, [args] { return run_aerial(*args); }};
}

}  // namespace welkin::cli
