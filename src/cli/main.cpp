// SPDX-License-Identifier: Apache-2.0
// The `welkin` command-line tool: sky HDRIs, sun radiometry and atmospheres without
// Blender. Thin by design: it parses, calls the core, and reports.
//
// Exit status: 0 on success; 2 for bad input (a usage error, an out-of-range value, an
// unknown preset, a malformed atmosphere file), with one line on stderr naming the option
// and its accepted range; 1 when the work itself fails (a file that cannot be written or
// read, a method that cannot run); 130 when interrupted (Ctrl-C). Nothing is ever written
// on failure, and no existing file is replaced without --overwrite.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <map>
#include <string>
#include <vector>

#include "common.hpp"
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace {

// Core parameter names as the user typed them on this command line.
std::string option_name(const std::string& parameter) {
    static const std::map<std::string, std::string> names = {
        {"width", "--width"},
        {"exposure", "--exposure"},
        {"altitude_m", "--altitude"},
        {"sun_direction", "--sun-elevation/--sun-azimuth"},
        {"preset", "--preset"},
        {"method", "--method"},
        {"reference_paths", "--reference-paths"}};
    const auto it = names.find(parameter);
    return it == names.end() ? parameter : it->second;
}

// Single-line messages: a message with newlines is joined.
std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
}

int run_guarded(const std::function<int()>& run) {
    try {
        return run();
    } catch (const welkin::Cancelled&) {
        fmt::print(stderr, "welkin: cancelled; nothing written\n");
        return 130;
    } catch (const welkin::InvalidArgument& e) {
        const std::string what = e.what(), prefix = e.parameter() + ": ";
        const std::string message = what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what;
        fmt::print(stderr, "welkin: error: {}: {}\n", option_name(e.parameter()), one_line(message));
        return 2;
    } catch (const std::exception& e) {
        // IoError names its path; anything else (e.g. a method that cannot run yet) is
        // reported as it comes.
        fmt::print(stderr, "welkin: error: {}\n", one_line(e.what()));
        return 1;
    }
}

// What was printed must have reached standard output (a full disk, a closed pipe,
// /dev/full): flush and close it, and fail with a message if either fails. `earlier`: the
// errno of a write that failed before (a flush while printing).
int finish_stdout(int status, int earlier = 0) {
    errno = 0;
    const bool failed = std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
    const int err = errno ? errno : earlier;
    const bool close_failed = std::fclose(stdout) != 0;
    if (failed || close_failed) {
        fmt::print(stderr, "welkin: error: cannot write to standard output: {}\n",
                   std::strerror(err     ? err
                                 : errno ? errno
                                         : EIO));
        return status == 0 ? 1 : status;
    }
    return status;
}

// CLI11's help and version text (std::cout, which writes through stdout and flushes it as
// it goes): printed, then checked as every command's output is.
int print_and_finish(CLI::App& app, const CLI::Error& e) {
    errno = 0;
    const int status = app.exit(e);
    return finish_stdout(status, std::ferror(stdout) ? errno : 0);
}

}  // namespace

int main(int argc, char** argv) {
    using namespace welkin::cli;
    CLI::App app{
        "welkin: physically based sky and atmosphere (sky HDRIs, sun radiometry, "
        "atmospheres). Units: SI; angles in degrees at this edge.",
        "welkin"};
    app.set_version_flag("--version", fmt::format("welkin {}", kVersion));
    app.require_subcommand(1);
    app.get_formatter()->column_width(34);
    const std::vector<Command> commands = {add_sky_command(app),      add_sun_command(app),
                                           add_presets_command(app),  add_atmosphere_command(app),
                                           add_exr_info_command(app), add_aerial_command(app),
                                           add_plate_command(app),    add_clouds_command(app)};
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return print_and_finish(app, e);
    } catch (const CLI::CallForAllHelp& e) {
        return print_and_finish(app, e);
    } catch (const CLI::CallForVersion& e) {
        return print_and_finish(app, e);
    } catch (const CLI::ParseError& e) {
        std::string where = "welkin";
        for (const Command& c : commands)
            if (c.app->parsed()) where += " " + c.app->get_name();
        fmt::print(stderr, "welkin: error: {} (see `{} --help`)\n", one_line(e.what()), where);
        return 2;
    }
    for (const Command& c : commands)
        if (c.app->parsed()) return finish_stdout(run_guarded(c.run));
    return 2;  // unreachable: require_subcommand(1)
}
