// SPDX-License-Identifier: Apache-2.0
// Files in and out, bounded and atomic: the one place where Welkin reads an input file
// whole and replaces an output file (every writer: EXR, atmosphere and scene JSON).
//
// Reading: InputFile and read_file_bounded refuse what is not a regular file (a directory, a device such
// as /dev/zero, a FIFO, a socket) and a file larger than the limit, before reading it.
//
// Writing: an output path that is a symlink is written through (the file it points to is
// replaced, atomically, next to that file: the link stays); a path that is a directory or
// another special file (character or block device, FIFO, socket) is refused, overwrite or
// not. The data goes to a unique temporary file (mkstemp) in the target's folder, which is
// moved into place only when complete; on any failure, and on cancellation, it is removed.
// Without overwrite, an existing file is never replaced, even one that appears during the
// write. Failures raise IoError naming the path and the reason (strerror).
//
// The limits are documented in docs/limits.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "welkin/base/error.hpp"

namespace welkin {

// The largest JSON file (atmosphere, scene) Welkin reads.
inline constexpr std::size_t kMaxJsonFileBytes = std::size_t(64) << 20;  // 64 MiB

// The whole of a regular file of at most `max_bytes` bytes. IoError naming `path` (and
// `what`, e.g. "atmosphere file") when it is missing, unreadable, a directory, not a regular
// file, or larger than max_bytes.
std::string read_file_bounded(const std::string& path, std::size_t max_bytes,
                              const std::string& what = "file");

// An open descriptor (read-only, close-on-exec) of the regular file `path`, and its size.
// IoError naming `path` (and `what`) when it is missing, unreadable, or a directory, device,
// FIFO or socket: opened with O_NONBLOCK, so a FIFO is refused at once, not waited on.
struct InputFile {
    InputFile(const std::string& path, const std::string& what);
    ~InputFile();
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;
    int fd = -1;
    std::uint64_t size = 0;
};

// An output path that names a directory or another special file (device, FIFO, socket).
class NotRegularFile : public IoError {
public:
    using IoError::IoError;
};

// The file an output path really names: symlinks followed (to their final target, which may
// not exist yet). NotRegularFile naming `path` for a directory or another special file;
// IoError for an
// existing file when !overwrite, and for a folder that does not exist.
std::filesystem::path resolve_output_path(const std::string& path, bool overwrite);

// A unique temporary file beside an output (mkstemp in the target's folder, named
// ".<name>.welkin-XXXXXX", created with the target's mode or 0666 & ~umask). Removed by the
// destructor unless committed; registered so that remove_temporaries_signal_safe() can
// remove it from a signal handler.
class TemporaryFile {
public:
    // `target`: a resolved output path (resolve_output_path); `path` names it in errors.
    TemporaryFile(const std::filesystem::path& target, const std::string& path);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;

    const std::filesystem::path& path() const { return tmp_; }
    // The open descriptor (the file is empty); close_fd() closes it (idempotent).
    int fd() const { return fd_; }
    void close_fd();
    // Writes all of `data` to the descriptor, flushes it to disk and closes it.
    void write_all(const void* data, std::size_t size);
    // Moves the temporary into place: replaces the target when overwrite, else refuses (an
    // IoError) when a file appeared there meanwhile. The temporary is gone afterwards.
    void commit(bool overwrite);
    // Removes the temporary now (idempotent).
    void discard() noexcept;

private:
    std::filesystem::path target_, tmp_;
    std::string name_;
    int fd_ = -1;
    int slot_ = -1;
    bool done_ = false;
};

// Writes `text` to `path` through a TemporaryFile: resolve_output_path, then commit.
void write_file_atomic(const std::string& path, const std::string& text, bool overwrite);

// Unlinks every live TemporaryFile of this process. Async-signal-safe: for a handler of
// SIGINT/SIGTERM that is about to end the process (the CLI's second Ctrl-C).
void remove_temporaries_signal_safe() noexcept;

}  // namespace welkin
