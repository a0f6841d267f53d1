// SPDX-License-Identifier: Apache-2.0
// JSON parsing with the key path of a failure, bounded file reads, atomic writes; see json.hpp.
#include "welkin/io/json.hpp"

#include <vector>

#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/io/file.hpp"

namespace welkin {
namespace {

using nlohmann::json;

// Where the parser is: one frame per open array or object.
struct Frame {
    bool array = false;
    std::size_t index = 0;  // arrays: the element being read
    std::string key;        // objects: the last key read
};

std::string path_of(const std::vector<Frame>& frames) {
    std::string p;
    for (const Frame& f : frames) {
        if (f.array)
            p += fmt::format("[{}]", f.index);
        else if (!f.key.empty())
            p += (p.empty() ? "" : ".") + f.key;
    }
    return p;
}

// Past the limit the parse stops with this (caught below; never escapes).
struct TooDeep {};

}  // namespace

json parse_json(const std::string& text, const std::string& what, const std::string& source) {
    std::vector<Frame> frames;
    const auto completed = [&] {
        if (!frames.empty() && frames.back().array) ++frames.back().index;
    };
    const json::parser_callback_t track = [&](int depth, json::parse_event_t event, json& parsed) {
        switch (event) {
            case json::parse_event_t::object_start:
            case json::parse_event_t::array_start:
                if (depth >= kMaxJsonDepth) throw TooDeep{};
                frames.push_back({event == json::parse_event_t::array_start, 0, {}});
                break;
            case json::parse_event_t::object_end:
            case json::parse_event_t::array_end:
                if (!frames.empty()) frames.pop_back();
                completed();
                break;
            case json::parse_event_t::key:
                if (!frames.empty()) frames.back().key = parsed.is_string() ? parsed.get<std::string>() : "";
                break;
            case json::parse_event_t::value:
                completed();
                break;
        }
        return true;
    };
    const std::string in = source.empty() ? "" : fmt::format(" in '{}'", source);
    const auto parameter = [&] {
        const std::string p = path_of(frames);
        return p.empty() ? what : p;
    };
    try {
        return json::parse(text, track, /*allow_exceptions=*/true, /*ignore_comments=*/false);
    } catch (const TooDeep&) {
        throw InvalidArgument(parameter(), fmt::format("nested deeper than {} levels{}", kMaxJsonDepth, in));
    } catch (const json::out_of_range& e) {
        // "number overflow parsing '1e999'": the number is the part in quotes.
        const std::string m = e.what();
        const auto a = m.find('\''), b = m.rfind('\'');
        const std::string number = a != std::string::npos && b > a ? m.substr(a + 1, b - a - 1) : "";
        throw InvalidArgument(parameter(), fmt::format("number out of range{}{}",
                                                       number.empty() ? "" : " (" + number + ")", in));
    } catch (const json::parse_error& e) {
        // nlohmann's text: "[json.exception.parse_error.101] parse error at line 1, column 2: ..."
        std::string m = e.what();
        const auto p = m.find("] ");
        if (p != std::string::npos) m = m.substr(p + 2);
        throw InvalidArgument(parameter(), fmt::format("malformed JSON{} at byte {}: {}", in, e.byte, m));
    } catch (const json::exception& e) {
        throw InvalidArgument(parameter(), fmt::format("malformed JSON{}: {}", in, e.what()));
    }
}

double json_number(const json& j, const std::string& parameter) {
    if (!j.is_number()) throw InvalidArgument(parameter, fmt::format("must be a number, got {}", j.dump()));
    return j.get<double>();
}

void json_check_keys(const json& j, const std::string& where, std::initializer_list<const char*> known) {
    if (!j.is_object()) throw InvalidArgument(where.empty() ? "JSON" : where, "must be a JSON object");
    for (const auto& [key, _] : j.items()) {
        bool ok = false;
        for (const char* k : known) ok = ok || key == k;
        if (!ok) throw InvalidArgument(where.empty() ? key : where + "." + key, "unknown key (a typo?)");
    }
}

json read_json_file(const std::string& path, const std::string& what) {
    const std::string text = read_file_bounded(path, kMaxJsonFileBytes, what + " file");
    return parse_json(text, what, path);
}

void write_json_file(const std::string& path, const std::string& text, bool overwrite) {
    write_file_atomic(path, text + "\n", overwrite);
}

}  // namespace welkin
