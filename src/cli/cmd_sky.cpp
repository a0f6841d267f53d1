// SPDX-License-Identifier: Apache-2.0
// `welkin sky`: render an equirectangular sky HDRI to OpenEXR.
#include <algorithm>
#include <charconv>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>

#include "common.hpp"
#include "place_and_time.hpp"
#include "terminal_progress.hpp"
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "welkin/base/error.hpp"
#include "welkin/color/reflectance.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/night/moonlit_sky.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/night/stars.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/scene/scene.hpp"
#include "welkin/sky/auto.hpp"

namespace welkin::cli {
namespace {

struct SkyArgs {
    AtmosphereArgs atmosphere;
    ObserverArgs observer;
    int width = 2048;
    std::string method = "auto";
    double tolerance = SkyOptions{}.tolerance;
    double exposure = 1.0;
    bool half = false, full_float = false;
    bool no_sun_disc = false;
    bool stars = true;  // with --time: the catalogue's stars
    bool ground = true;
    std::optional<double> ground_albedo;
    std::vector<double> ground_color;  // --ground-color R,G,B: empty unless given
    bool multilayer = false;
    bool spectral_channels = false;
    bool overwrite = false;
    std::string output = "welkin_sky.exr";
    int threads = 0;
    int reference_paths = SkyOptions{}.reference_paths;
    std::uint64_t seed = SkyOptions{}.seed;
    std::string scene;         // a scene JSON replaces the atmosphere, sun, method and exposure options
    std::string color_space;   // empty: the scene's, else rec709
    PlaceTimeArgs place_time;  // --time, --latitude, --longitude: the sun from a place and a moment
};

// The sky's settings from --scene: atmosphere, observer at the scene origin, sky method and
// its options, exposure. Errors name --scene and the key.
struct SkySettings {
    Atmosphere atmosphere;
    Observer observer;
    SkyOptions options;
    std::string method{};
    double exposure = 1.0;
    ColorSpace color_space = ColorSpace::Rec709;
    std::shared_ptr<const CloudDensity> clouds{};  // the scene's (none without --scene)
    bool ground = true;                            // the scene's ground (--no-ground wins)
    std::optional<double> ground_albedo{};         // the scene's (--ground-albedo wins)
    CloudLightingOptions cloud_lighting{};
    CloudUpsampling cloud_upsampling{};
    int air_steps = AerialOptions{}.raymarch_steps;  // the air in front of the clouds
    std::size_t cloud_layers = 0, cloud_volumes = 0;
};

// --seed: digits only, within an unsigned 64-bit integer (CLI11 would otherwise take -1 or
// 1e23 and saturate them silently).
CLI::Validator seed_validator() {
    return CLI::Validator(
        [](std::string& value) -> std::string {
            const std::string range = "an integer in [0, 18446744073709551615]";
            std::uint64_t v = 0;
            const char* end = value.data() + value.size();
            const auto [ptr, ec] = std::from_chars(value.data(), end, v);
            if (value.empty() || value[0] == '-' || value[0] == '+' || ec != std::errc() || ptr != end)
                return fmt::format("must be {}, got '{}'", range, value);
            return {};
        },
        "UINT64");
}

SkySettings settings_from(const SkyArgs& args) {
    if (args.scene.empty()) {
        SkyOptions options;
        options.reference_paths = args.reference_paths;
        options.seed = args.seed;
        SkySettings out{load_atmosphere(args.atmosphere), make_observer(args.observer), options};
        out.method = args.method;
        out.exposure = args.exposure;
        return out;
    }
    try {
        const SceneDescription scene = SceneDescription::from_json_file(args.scene);
        SkySettings out{scene.atmosphere, scene.origin_observer(), scene.sky_options};
        out.method = scene.method;
        out.exposure = scene.exposure;
        out.color_space = scene.color_space;
        // The scene's clouds (VDBs opened now, before the render), seen from the scene origin.
        out.clouds = scene.cloud_density();
        out.ground = scene.ground;
        out.ground_albedo = scene.ground_albedo;
        if (scene.clouds) {
            out.cloud_lighting = scene.clouds->lighting;
            out.cloud_upsampling = scene.clouds->upsampling;
            out.air_steps = scene.aerial.raymarch_steps;
            out.cloud_layers = scene.clouds->layers.size();
            out.cloud_volumes = scene.clouds->volumes.size();
        }
        return out;
    } catch (const InvalidArgument& e) {
        throw InvalidArgument("--scene", fmt::format("{} (in '{}')", e.what(), args.scene));
    } catch (const IoError& e) {
        throw InvalidArgument("--scene", e.what());
    }
}

// The settings that reproduce the file (its welkinSettings attribute).
nlohmann::ordered_json provenance(const SkyArgs& args, const SkySettings& sky, const Atmosphere& atm,
                                  const Observer& observer, const std::string& method_name,
                                  ColorSpace color_space, const std::optional<PlaceTime>& place_time) {
    nlohmann::ordered_json settings = {
        {"atmosphere", !args.scene.empty()            ? atm.name
                       : args.atmosphere.file.empty() ? atm.name
                                                      : args.atmosphere.file},
        {"wavelengths_nm", atm.wavelengths_nm},
        {"sun_direction", {observer.sun_direction.x, observer.sun_direction.y, observer.sun_direction.z}},
        {"altitude_m", observer.altitude_m},
        {"method", method_name},
        {"requested_method", sky.method},
        {"tolerance", args.tolerance},
        {"exposure", sky.exposure},
        {"sun_disc", !args.no_sun_disc},
        {"ground", args.ground},
        {"stars", place_time.has_value() && args.stars},
        {"ground_albedo", args.ground_albedo           ? nlohmann::json(*args.ground_albedo)
                          : !args.ground_color.empty() ? nlohmann::json({{"color", args.ground_color}})
                                                       : nlohmann::json("atmosphere")},
        {"clouds", {{"layers", sky.cloud_layers}, {"volumes", sky.cloud_volumes}}},
        {"units", args.spectral_channels ? std::string("W m^-2 sr^-1 nm^-1 (times exposure)")
                                         : fmt::format("linear {}, W m^-2 sr^-1 (times exposure)",
                                                       color_space_name(color_space))}};
    if (place_time) settings["place_and_time"] = place_time->json();
    if (args.scene.empty()) {
        settings["sun_elevation_deg"] = args.observer.sun_elevation_deg;
        settings["sun_azimuth_deg"] = args.observer.sun_azimuth_deg;
    } else {
        settings["scene"] = args.scene;
    }
    return settings;
}

int run_sky(SkyArgs args) {
    // Everything that can be refused is refused before the render starts.
    check_output_path(args.output, args.overwrite);
    const std::optional<PlaceTime> place_time = resolve_place_time(args.place_time, args.observer);
    SkySettings sky = settings_from(args);
    if (place_time && !args.scene.empty()) {
        // The place and the moment place the sun (and the moon) in the scene's frame (+Y
        // north, +X east), under the scene's clouds.
        const auto& d = place_time->sky.sun.direction_enu;
        sky.observer.sun_direction = {d[0], d[1], d[2]};
        sky.observer = sky.observer.validated();
    }
    const ColorSpace color_space =
        args.color_space.empty() ? sky.color_space : color_space_from_name(args.color_space);
    Atmosphere atm = sky.atmosphere;
    if (!args.ground_color.empty()) {
        // The colour's reflectance spectrum (color/reflectance.hpp), in the output's colour
        // space, as the ground's albedo everywhere it counts: the image below the horizon and
        // the light the ground sends back up into the sky.
        atm.ground_albedo =
            rgb_to_reflectance({args.ground_color[0], args.ground_color[1], args.ground_color[2]},
                               atm.wavelengths_nm, color_space, "--ground-color");
    }
    const Observer& observer = sky.observer;
    SkyOptions options = sky.options;
    options.tolerance = args.tolerance;
    std::string method_name = sky.method;
    std::optional<AutoChoice> choice;
    if (method_name == "auto") {
        // Resolved here, once for the whole image, so that it can be reported (after the
        // render, so that a refusal is the only thing a bad command prints).
        choice = choose_sky_method(atm, observer, std::size_t(args.width) * std::size_t(args.width / 2),
                                   args.tolerance, options);
        options = choice->options;
        method_name = choice->method;
    }
    const std::unique_ptr<SkyMethod> method = make_sky_method(method_name, options);
    SkyImageOptions image_options;
    image_options.sun_disc = !args.no_sun_disc;
    image_options.ground = args.ground && sky.ground;
    // A scene's grey albedo would hide --ground-color's spectrum (image_options' albedo wins).
    image_options.ground_albedo = args.ground_albedo
                                      ? args.ground_albedo
                                      : (args.ground_color.empty() ? sky.ground_albedo : std::nullopt);
    image_options.exposure = sky.exposure;
    image_options.color_space = color_space;
    image_options.output =
        args.spectral_channels ? SkyImageOptions::Output::Spectral : SkyImageOptions::Output::Rgb;
    image_options.clouds = sky.clouds;
    image_options.cloud_lighting = sky.cloud_lighting;
    image_options.cloud_upsampling = sky.cloud_upsampling;
    image_options.air_steps = sky.air_steps;
    image_options.validate();

    const auto threads = limit_threads(args.threads);

    install_interrupt_handler();
    const auto start = std::chrono::steady_clock::now();
    SkyImage image;
    {
        TerminalProgress progress(fmt::format("sky {}x{} ({})", args.width, args.width / 2, method_name));
        if (place_time) {
            // The moment's sky: the sun's and the moon's (night/moonlit_sky.hpp).
            Moon moon = moon_at(place_time->sky);
            moon.disc = image_options.sun_disc;
            image = render_equirect_sky_with_moon(*method, atm, observer, moon, args.width, image_options,
                                                  &progress);
            const Instant when = Instant::from_civil(place_time->time, "--time");
            NightGlowOptions glow;
            glow.ecliptic = ecliptic_frame(when, place_time->place);
            add_night_glow(image, atm, observer, image_options, glow);
            if (args.stars) add_stars(image, atm, observer, stars_at(when, place_time->place), image_options);
        } else {
            image = render_equirect_sky(*method, atm, observer, args.width, image_options, &progress);
        }
        progress.finish();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (interrupted()) throw Cancelled();

    ExrImage exr;
    exr.width = image.width;
    exr.height = image.height;
    for (const std::string& name : image.channel_names)
        exr.channel_names.push_back(args.multilayer ? "Welkin.Sky." + name : name);
    exr.pixels = std::move(image.pixels);
    ExrWriteOptions write = exr_write_options(args.overwrite, args.half);
    const nlohmann::ordered_json settings =
        provenance(args, sky, atm, observer, method_name, color_space, place_time);
    write.attributes.emplace_back("welkinSettings", settings.dump());
    if (args.spectral_channels) write.attributes.emplace_back("emissiveUnits", "W.m^-2.sr^-1.nm^-1");
    const ExrWriteReport report = write_exr(args.output, exr, write);
    if (choice) {
        fmt::print("auto: {} (chart: p95 relative luminance error {:.3g} {} tolerance {:g})\n",
                   choice->setting, choice->predicted_error, choice->meets_tolerance ? "<=" : "ABOVE",
                   args.tolerance);
        if (!choice->meets_tolerance)
            fmt::print(stderr,
                       "welkin: warning: no fast method meets --tolerance {:g} for this scene; "
                       "used the closest ({}); --method reference is exact but slow\n",
                       args.tolerance, choice->setting);
    }
    if (report.clamped_values > 0)
        fmt::print(stderr,
                   "welkin: warning: {} values above 65504 (the sun's disc) were clamped in "
                   "the half-float file; use --float to keep them, or --exposure to scale\n",
                   report.clamped_values);
    fmt::print("wrote {} ({} x {}, {} {}, method {}, {:.2f} s)\n",
               std::filesystem::absolute(args.output).string(), exr.width, exr.height,
               fmt::join(exr.channel_names, ","), args.half ? "half" : "float", method_name, seconds);
    return 0;
}

}  // namespace

Command add_sky_command(CLI::App& app) {
    auto args = std::make_shared<SkyArgs>();
    CLI::App* sub = app.add_subcommand(
        "sky", "Render an equirectangular sky HDRI (OpenEXR) for Blender's Environment Texture");
    add_atmosphere_options(sub, args->atmosphere);
    add_observer_options(sub, args->observer);
    add_place_time_options(sub, args->place_time);
    sub->add_option("--width", args->width,
                    "Image width in pixels, even, in [4, 16384]; the height is width / 2")
        ->type_name("W")
        ->check(CLI::Range(4, 16384))
        ->capture_default_str();
    sub->add_option("--method", args->method,
                    "Sky method: auto (the cheapest that the speed-accuracy chart shows "
                    "meeting --tolerance), analytic, lut (Hillaire 2020), raymarch, or "
                    "reference (Monte-Carlo, slow)")
        ->type_name("NAME")
        ->check(CLI::IsMember(sky_method_names()))
        ->capture_default_str();
    sub->add_option("--tolerance", args->tolerance,
                    "auto method: relative luminance error to meet (95th percentile over the "
                    "sphere, against the reference), in [0.001, 10]")
        ->type_name("X")
        ->capture_default_str();
    add_color_space_option(sub, args->color_space);
    sub->add_option("--exposure", args->exposure,
                    "Multiplies every output value (sky and sun) once, after colour "
                    "conversion; in (0, 1e6]. 1 keeps physical units: linear Rec.709 in "
                    "W m^-2 sr^-1, the scale of Blender's Nishita sky (683 gives cd m^-2)")
        ->type_name("X")
        ->capture_default_str();
    auto* half = sub->add_flag("--half", args->half,
                               "Write 16-bit half floats (smaller; values above 65504, such "
                               "as the sun's disc, are clamped)");
    auto* full = sub->add_flag("--float", args->full_float, "Write 32-bit floats (the default)");
    half->excludes(full);
    sub->add_flag("--no-sun-disc", args->no_sun_disc,
                  "Leave the sun's disc out (when a sun lamp lights the scene, so that its "
                  "energy is not counted twice)");
    sub->add_flag("--stars,!--no-stars", args->stars,
                  "With --time: the stars of V <= 7 of the Hipparcos catalogue at their apparent "
                  "places, dimmed by the air (the default), or none (--no-stars)");
    sub->add_flag("--ground,!--no-ground", args->ground,
                  "Show the planet's surface below the horizon, lit by the sun and the sky and "
                  "seen through the air (the default), or leave it black (--no-ground)");
    auto* albedo = sub->add_option("--ground-albedo", args->ground_albedo,
                                   "The ground's albedo in [0, 1] at every wavelength (default: the "
                                   "atmosphere's ground_albedo)")
                       ->type_name("A");
    sub->add_option("--ground-color", args->ground_color,
                    "The ground's colour instead of a grey: linear R,G,B each in [0, 1] in the output's "
                    "colour space, turned into a smooth reflectance spectrum (Jakob & Hanika 2019) "
                    "that lights the sky above it too")
        ->type_name("R,G,B")
        ->delimiter(',')
        ->expected(3)
        ->excludes(albedo);
    sub->add_flag("--multilayer", args->multilayer,
                  "Name the channels Welkin.Sky.R/G/B (a Blender multilayer EXR) instead of "
                  "R/G/B");
    sub->add_flag("--spectral-channels", args->spectral_channels,
                  "Write one channel per wavelength (W m^-2 sr^-1 nm^-1, named S0.<nm>nm as "
                  "in the spectral OpenEXR layout) instead of RGB");
    sub->add_flag("--overwrite", args->overwrite, "Replace the output file if it exists");
    sub->add_option("-o,--output", args->output, "Output EXR file; never replaced unless --overwrite")
        ->type_name("FILE.exr")
        ->capture_default_str();
    sub->add_option("--threads", args->threads, "Worker threads, in [1, 1024] (default: all cores)")
        ->type_name("N")
        ->check(CLI::Range(1, 1024));
    sub->add_option("--reference-paths", args->reference_paths,
                    "reference method: Monte-Carlo paths per pixel and wavelength")
        ->type_name("N")
        ->check(CLI::Range(1, 1 << 26))
        ->capture_default_str();
    sub->add_option("--seed", args->seed, "reference method: random seed, an integer in [0, 2^64 - 1]")
        ->type_name("N")
        ->check(seed_validator())
        ->capture_default_str();
    auto* scene = sub->add_option("--scene", args->scene,
                                  "Take the atmosphere, the sun, the observer altitude (the scene "
                                  "origin's), the method, the exposure and the clouds (layers, "
                                  "VDB volumes, their lighting) from a scene JSON (the schema "
                                  "`welkin aerial` reads); replaces those options. With --time the "
                                  "place and the moment place the sun instead, and the moon lights "
                                  "the clouds; the stars and the night glow shine through them")
                      ->type_name("FILE.json");
    for (const char* name : {"--preset", "--atmosphere", "--spectral", "--aerosol-optical-depth",
                             "--turbidity", "--sun-elevation", "--sun-azimuth", "--altitude", "--method",
                             "--exposure", "--reference-paths", "--seed"})
        scene->excludes(sub->get_option(name));
    sub->footer(
        "The image covers the whole sphere: top row the zenith, +X at the centre, +Y a "
        "quarter from the left (Blender's mapping). Sky radiance excludes the sun's disc; "
        "the disc is added with its exact direct irradiance (see `welkin sun`). Ctrl-C "
        "cancels cleanly; nothing is written.");
    return {sub, [args] { return run_sky(*args); }};
}

}  // namespace welkin::cli
