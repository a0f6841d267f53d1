// SPDX-License-Identifier: Apache-2.0
// `welkin presets` and `welkin atmosphere`: list the built-in atmospheres, write one (or a
// normalised JSON file) as JSON.
#include <filesystem>
#include <memory>

#include "common.hpp"
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "welkin/atmosphere/aerosol.hpp"

namespace welkin::cli {
namespace {

struct PresetsArgs {
    bool json = false;
};

int run_presets(const PresetsArgs& args) {
    const std::vector<std::string> names = Atmosphere::preset_names();
    if (args.json) {
        fmt::print("{}\n", nlohmann::json(names).dump());
        return 0;
    }
    for (const std::string& name : names) {
        const Atmosphere a = Atmosphere::preset(name);
        fmt::print(
            "{:14} aerosol optical depth at 550 nm {:.3f}, ground radius {:.0f} km, atmosphere "
            "{:.0f} km thick, Mie g {}{}\n",
            name, aerosol_optical_depth(a, 550.0), a.bottom_radius_m / 1e3, a.atmosphere_thickness_m() / 1e3,
            a.mie_g, name == kDefaultPreset ? " (default)" : "");
    }
    return 0;
}

struct AtmosphereCmdArgs {
    AtmosphereArgs atmosphere;
    std::string output;
    bool overwrite = false;
};

int run_atmosphere(const AtmosphereCmdArgs& args) {
    const Atmosphere atm = load_atmosphere(args.atmosphere);
    if (args.output.empty() || args.output == "-") {
        fmt::print("{}\n", atm.to_json_string());
        return 0;
    }
    check_output_path(args.output, args.overwrite);
    atm.to_json_file(args.output, args.overwrite);
    fmt::print("wrote {}\n", std::filesystem::absolute(args.output).string());
    return 0;
}

}  // namespace

Command add_presets_command(CLI::App& app) {
    auto args = std::make_shared<PresetsArgs>();
    CLI::App* sub = app.add_subcommand("presets", "List the built-in atmospheres");
    sub->add_flag("--json", args->json, "Print the names as a JSON array");
    return {sub, [args] { return run_presets(*args); }};
}

Command add_atmosphere_command(CLI::App& app) {
    auto args = std::make_shared<AtmosphereCmdArgs>();
    CLI::App* sub = app.add_subcommand("atmosphere",
                                       "Write an atmosphere as JSON (a preset, or a JSON file in full form)");
    add_atmosphere_options(sub, args->atmosphere);
    sub->add_option("-o,--output", args->output,
                    "Output JSON file (default: standard output); never replaced unless "
                    "--overwrite")
        ->type_name("FILE.json");
    sub->add_flag("--overwrite", args->overwrite, "Replace the output file if it exists");
    sub->footer(
        "Edit the file and pass it back with --atmosphere to `welkin sky` or `welkin "
        "sun`. Units: metres, m^-1, W m^-2 nm^-1.");
    return {sub, [args] { return run_atmosphere(*args); }};
}

}  // namespace welkin::cli
