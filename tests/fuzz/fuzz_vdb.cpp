// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the VDB reader (clouds/vdb) on arbitrary bytes, written to a file as
// a user's .vdb would be. Any outcome but a valid grid or a welkin error (IoError,
// InvalidArgument, OutOfMemory naming the file) is a bug. The memory limit is small, so a
// corrupt grid must be refused by the checks before its tree is read, not by running out.
// Built and run by scripts/fuzz.sh; the seed corpus is tests/fuzz/corpus/vdb/.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>

#include <pthread.h>
#include <sanitizer/common_interface_defs.h>
#include <unistd.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/vdb.hpp"

// OpenVDB sizes buffers from lengths inside the grid's tree (a corrupt blosc chunk declares
// 2^56 bytes). Outside the fuzzer such a request fails with std::bad_alloc, which Welkin
// reports as OutOfMemory naming the file; AddressSanitizer's own operator new would abort
// instead. These replacements keep the program's behaviour (a request beyond 1 GiB
// throws, as a failed allocation does) while malloc and free stay ASan's.
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

// The reader parses a file's tree in a forked child (clouds/vdb.cpp, run_tree_reader): a
// corrupt tree that overflows a buffer inside OpenVDB is reported by ASan in the child, the
// child dies and the host refuses the file. That is the isolation doing its work, so in the
// child libFuzzer's death callback (which would save the input as a finding and print the
// fuzzer's statistics from a dying process) is removed; a crash of the host is still one.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
    // Which process a report in the log comes from (scripts/fuzz.sh puts this in its findings).
    std::fprintf(stderr, "fuzz_vdb: host process %d\n", int(::getpid()));
    ::pthread_atfork(nullptr, nullptr, [] { __sanitizer_set_death_callback(nullptr); });
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // One input file per process, in $TMPDIR: scripts/fuzz.sh points it at a folder it
    // removes after the run (libFuzzer ends the process without running atexit functions).
    static const std::string path =
        (std::filesystem::temp_directory_path() / ("welkin_fuzz_vdb_" + std::to_string(::getpid()) + ".vdb"))
            .string();
    if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
        std::fwrite(data, 1, size, f);
        std::fclose(f);
    } else {
        return 0;
    }
    welkin::VdbCloudOptions options;
    options.max_memory_bytes = std::uint64_t(64) << 20;
    try {
        welkin::VdbClouds clouds(path, options);
        (void)clouds.sigma_t({0.0, 0.0, 0.0});
    } catch (const welkin::IoError&) {
    } catch (const welkin::InvalidArgument&) {
    } catch (const welkin::OutOfMemory&) {
    }
    return 0;
}
