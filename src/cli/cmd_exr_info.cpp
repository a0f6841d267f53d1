// SPDX-License-Identifier: Apache-2.0
// `welkin exr-info`: what an EXR file holds, as JSON (size, channels and their statistics),
// so that scripts and tests can check a render without an OpenEXR binding.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "common.hpp"
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "welkin/base/equirect.hpp"
#include "welkin/io/exr.hpp"

namespace welkin::cli {
namespace {

struct ExrInfoArgs {
    std::string path;
    bool integral = false;
};

int run_exr_info(const ExrInfoArgs& args) {
    const ExrImage im = read_exr(args.path);
    const std::size_t nc = im.channels();
    const std::size_t n = std::size_t(im.width) * std::size_t(im.height);
    nlohmann::ordered_json channels = nlohmann::json::array();
    for (std::size_t c = 0; c < nc; ++c) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0, integral = 0.0;
        std::size_t non_finite = 0;
        for (int y = 0; y < im.height; ++y) {
            const double omega = args.integral ? equirect_pixel_solid_angle(y, im.width, im.height) : 0.0;
            for (int x = 0; x < im.width; ++x) {
                const double v = im.at(x, y, c);
                if (!std::isfinite(v)) {
                    ++non_finite;
                    continue;
                }
                lo = std::min(lo, v);
                hi = std::max(hi, v);
                sum += v;
                integral += v * omega;
            }
        }
        nlohmann::ordered_json ch = {{"name", im.channel_names[c]},
                                     {"min", n > non_finite ? lo : 0.0},
                                     {"max", n > non_finite ? hi : 0.0},
                                     {"mean", n > non_finite ? sum / double(n - non_finite) : 0.0},
                                     {"non_finite", non_finite}};
        if (args.integral) ch["solid_angle_integral"] = integral;
        channels.push_back(ch);
    }
    const nlohmann::ordered_json j = {
        {"path", args.path}, {"width", im.width}, {"height", im.height}, {"channels", channels}};
    fmt::print("{}\n", j.dump(2));
    return 0;
}

}  // namespace

Command add_exr_info_command(CLI::App& app) {
    auto args = std::make_shared<ExrInfoArgs>();
    CLI::App* sub =
        app.add_subcommand("exr-info", "Print an EXR file's size and per-channel statistics (JSON)");
    sub->add_option("file", args->path, "The EXR file")->required()->type_name("FILE.exr");
    sub->add_flag("--integral", args->integral,
                  "Also integrate each channel over the sphere as an equirectangular image "
                  "(sum of value x pixel solid angle): for a sky HDRI, W m^-2 sr^-1 -> W m^-2");
    return {sub, [args] { return run_exr_info(*args); }};
}

}  // namespace welkin::cli
