// SPDX-License-Identifier: Apache-2.0
// `welkin plate`: the scene camera's plate (camera_plate.hpp) from a scene JSON, as a
// multilayer OpenEXR: RGB (Combined) plus the layers Welkin.Sky, Welkin.AerialInscatter,
// Welkin.AerialTransmittance (R, G, B each), Welkin.Clouds (R, G, B, A), Welkin.CloudDepth
// (Z) and Z (depth to the ground, +inf on sky).
// The same plate the Blender render engine "WELKIN" renders.
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>

#include "common.hpp"
#include "terminal_progress.hpp"
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "welkin/base/error.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/render/camera_plate.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::cli {
namespace {

int run_plate(const SceneOutputArgs& args) {
    check_output_path(args.output, args.overwrite);
    const SceneDescription scene = load_camera_scene(args.scene);
    const auto threads = limit_threads(args.threads);

    install_interrupt_handler();
    const auto start = std::chrono::steady_clock::now();
    CameraPlate plate;
    {
        TerminalProgress progress(
            fmt::format("plate {}x{}", scene.resolution.width(), scene.resolution.height()));
        try {
            plate = render_camera_plate(scene, &progress);
        } catch (const InvalidArgument& e) {
            throw InvalidArgument("--scene", fmt::format("{} (in '{}')", e.what(), args.scene));
        }
        progress.finish();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (interrupted()) throw Cancelled();

    ExrImage exr;
    exr.width = plate.width;
    exr.height = plate.height;
    const std::vector<std::pair<std::string, const std::vector<float>*>> layers = {
        {"", &plate.combined},
        {"Welkin.Sky.", &plate.sky},
        {"Welkin.AerialInscatter.", &plate.inscatter},
        {"Welkin.AerialTransmittance.", &plate.transmittance}};
    for (const auto& [prefix, data] : layers)
        for (const char* c : {"R", "G", "B"}) exr.channel_names.push_back(prefix + c);
    for (const std::string& c : cloud_channel_names()) exr.channel_names.push_back(c);
    exr.channel_names.push_back("Z");
    const std::size_t n = std::size_t(plate.width) * std::size_t(plate.height);
    const std::size_t nch = exr.channel_names.size(), clouds_at = layers.size() * 3;
    exr.pixels.resize(n * nch);
    for (std::size_t p = 0; p < n; ++p) {
        for (std::size_t l = 0; l < layers.size(); ++l)
            for (int c = 0; c < 3; ++c) exr.pixels[p * nch + l * 3 + c] = (*layers[l].second)[p * 3 + c];
        for (int c = 0; c < 4; ++c) exr.pixels[p * nch + clouds_at + c] = plate.clouds[p * 4 + c];
        exr.pixels[p * nch + clouds_at + 4] = plate.cloud_depth[p];
        exr.pixels[p * nch + nch - 1] = plate.depth[p];
    }
    ExrWriteOptions write = exr_write_options(args, scene);
    write.attributes.insert(write.attributes.end(),
                            {{"welkinMethod", plate.method},
                             {"welkinUnits",
                              "linear Rec.709, W m^-2 sr^-1 (times exposure); "
                              "AerialTransmittance dimensionless; Clouds premultiplied; "
                              "Z, CloudDepth metres (1e10: no cloud)"}});
    write_exr(args.output, exr, write);
    fmt::print("wrote {} ({} x {}, sky method {}, {:.2f} s)\n",
               std::filesystem::absolute(args.output).string(), plate.width, plate.height, plate.method,
               seconds);
    return 0;
}

}  // namespace

Command add_plate_command(CLI::App& app) {
    auto args = std::make_shared<SceneOutputArgs>();
    args->output = "welkin_plate.exr";
    CLI::App* sub =
        app.add_subcommand("plate",
                           "The scene camera's plate: sky, sun disc and aerial perspective over the "
                           "ground (no meshes), as the Blender render engine \"Welkin\" renders it");
    add_scene_output_options(sub, *args,
                             "Scene description JSON with a camera (docs/pipelines.md \"Scene JSON\")");
    sub->footer(
        "Channels: R, G, B (Combined), Welkin.Sky.{R,G,B}, Welkin.AerialInscatter.{R,G,B}, "
        "Welkin.AerialTransmittance.{R,G,B}, Welkin.Clouds.{R,G,B,A} (premultiplied; alpha "
        "0 without \"clouds\" in the scene), Welkin.CloudDepth.Z (1e10 where no cloud), Z. "
        "Linear Rec.709, W m^-2 sr^-1, times the scene's exposure; top row first. With "
        "clouds, Combined = Clouds + (1 - Clouds.A) x the clear plate. Ctrl-C cancels; "
        "nothing is written.");
    return {sub, [args] { return run_plate(*args); }};
}

}  // namespace welkin::cli
