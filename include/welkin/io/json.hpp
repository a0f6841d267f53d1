// SPDX-License-Identifier: Apache-2.0
// JSON in and out, the one implementation the atmosphere and scene files share.
//
// read_json_file reads a bounded regular file (read_file_bounded: at most
// kMaxJsonFileBytes) and parses it; parse_json parses text. A parse failure raises
// InvalidArgument whose parameter is the key path where it happened ("rayleigh.density.
// layers[2].width_m"; the document's name, e.g. "atmosphere JSON", at the top level) and
// whose message says what went wrong ("number out of range (1e999)", "malformed: ...",
// "nested deeper than 64 levels") and where (the file and the byte). Read failures raise
// IoError naming the file. write_json_file writes through a unique temporary file
// (write_file_atomic). Limits: docs/limits.md.
#pragma once

#include <initializer_list>
#include <string>

#include <nlohmann/json.hpp>

namespace welkin {

// The deepest nesting of arrays and objects accepted in a JSON document.
inline constexpr int kMaxJsonDepth = 64;

// `what` names the document in errors ("atmosphere JSON"); `source` the file it came from
// (empty for a string).
nlohmann::json parse_json(const std::string& text, const std::string& what, const std::string& source = "");

// IoError naming the file when it cannot be read (missing, a directory, a device, too large);
// InvalidArgument as parse_json.
nlohmann::json read_json_file(const std::string& path, const std::string& what);

// `text` plus a newline, atomically (write_file_atomic).
void write_json_file(const std::string& path, const std::string& text, bool overwrite);

// The value helpers both schemas use. InvalidArgument naming `parameter`:
// json_number: not a number; json_check_keys: not an object, or a key not in `known` (a
// typo would otherwise be ignored; the error names "where.key").
double json_number(const nlohmann::json& j, const std::string& parameter);
void json_check_keys(const nlohmann::json& j, const std::string& where,
                     std::initializer_list<const char*> known);

// Runs f; an InvalidArgument it throws gets " (in 'path')" appended to its message.
template <class F>
auto with_json_source(const std::string& path, F&& f) -> decltype(f());

}  // namespace welkin

#include "welkin/base/error.hpp"

namespace welkin {

template <class F>
auto with_json_source(const std::string& path, F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const InvalidArgument& e) {
        const std::string what = e.what(), own = e.parameter() + ": ";
        const std::string message = what.rfind(own, 0) == 0 ? what.substr(own.size()) : what;
        if (message.find("'" + path + "'") != std::string::npos) throw;
        throw InvalidArgument(e.parameter(), message + " (in '" + path + "')");
    }
}

}  // namespace welkin
