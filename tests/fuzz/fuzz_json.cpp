// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the atmosphere and scene JSON readers (io/json, atmosphere/json,
// scene/json) on arbitrary bytes. Any outcome but a value or a welkin error is a bug: a
// crash, a sanitizer report, an uncaught exception (std::terminate), a leak, a hang.
// Built and run by scripts/fuzz.sh; the seed corpus is tests/fuzz/corpus/json/.
#include <cstddef>
#include <cstdint>
#include <string>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"
#include "welkin/scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        (void)welkin::Atmosphere::from_json_string(text);
    } catch (const welkin::InvalidArgument&) {
    } catch (const welkin::IoError&) {
    }
    try {
        // No base directory: relative VDB paths stay relative and are never opened here.
        (void)welkin::SceneDescription::from_json_string(text);
    } catch (const welkin::InvalidArgument&) {
    } catch (const welkin::IoError&) {
    }
    return 0;
}
