// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the OpenEXR reader (io/exr) on arbitrary bytes, written to a file as a
// user's render or depth file would be, and read the ways Welkin reads one: as an image
// (read_exr: the add-on's renders, `welkin exr-info`) and as a depth input (the header, then
// one channel: `welkin aerial --depth`, `welkin clouds --depth`). Any outcome but an image
// or a welkin error (IoError, InvalidArgument, OutOfMemory naming the file) is a bug.
// Built and run by scripts/fuzz.sh; the seed corpus is tests/fuzz/corpus/exr/.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>

#include <unistd.h>

#include "welkin/base/error.hpp"
#include "welkin/io/exr.hpp"

// A corrupt header declares a data window of any size. Outside the fuzzer an allocation
// beyond the machine's memory fails with std::bad_alloc, which Welkin reports as
// OutOfMemory naming the file; AddressSanitizer's own operator new would abort instead.
// These replacements keep the program's behaviour (a request beyond 1 GiB throws, as a
// failed allocation does) while malloc and free stay ASan's.
namespace {
void* allocate(std::size_t n) {
    if (n > (std::size_t(1) << 30)) throw std::bad_alloc();
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
}  // namespace
void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
    try {
        return allocate(n);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace {

// The images decoded whole: at most this many values (the rest stop at the header, as a
// depth file of the wrong size stops at the CLI's size check).
constexpr double kMaxValues = 1 << 22;

template <typename Read>
void guarded(Read read) {
    try {
        read();
    } catch (const welkin::IoError&) {
    } catch (const welkin::InvalidArgument&) {
    } catch (const welkin::OutOfMemory&) {
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // One input file per process, in $TMPDIR: scripts/fuzz.sh points it at a folder it
    // removes after the run (libFuzzer ends the process without running atexit functions).
    static const std::string path =
        (std::filesystem::temp_directory_path() / ("welkin_fuzz_exr_" + std::to_string(::getpid()) + ".exr"))
            .string();
    if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(data, 1, size, f);
        std::fclose(f);
    } else {
        return 0;
    }
    guarded([&] {
        const welkin::ExrHeaderInfo header = welkin::read_exr_header(path);
        const double values = double(header.width) * double(header.height);
        if (header.channel_names.empty() || values * double(header.channel_names.size()) > kMaxValues) return;
        // The depth input: the header, then one channel (the first, as the CLI reads Z).
        (void)welkin::read_exr_channels(path, {header.channel_names.front()});
        (void)welkin::read_exr(path);
    });
    return 0;
}
