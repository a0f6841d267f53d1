// SPDX-License-Identifier: Apache-2.0
// Bounded reads and atomic writes; see file.hpp.
#include "welkin/io/file.hpp"

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include "welkin/base/error.hpp"

namespace welkin {
namespace {

namespace fs = std::filesystem;

std::string reason(int err) { return std::strerror(err); }

// What a file that is not a regular one is, for messages.
const char* kind_of(mode_t mode) {
    if (S_ISDIR(mode)) return "a directory";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
    if (S_ISSOCK(mode)) return "a socket";
    return "not a regular file";
}

// Live temporaries, for remove_temporaries_signal_safe: fixed storage, no allocation.
constexpr int kSlots = 64;
struct Slot {
    std::atomic<bool> used{false};
    std::array<char, 4096> path{};
};
std::array<Slot, kSlots> g_slots;
std::mutex g_slots_mutex;

int register_temporary(const fs::path& p) {
    const std::string s = p.string();
    if (s.size() >= 4096) return -1;
    std::lock_guard lock(g_slots_mutex);
    for (int i = 0; i < kSlots; ++i) {
        if (g_slots[i].used.load()) continue;
        std::memcpy(g_slots[i].path.data(), s.c_str(), s.size() + 1);
        g_slots[i].used.store(true);
        return i;
    }
    return -1;  // more than kSlots writes at once: still removed on failure, not on a signal
}

void unregister_temporary(int slot) {
    if (slot < 0) return;
    std::lock_guard lock(g_slots_mutex);
    g_slots[slot].used.store(false);
}

mode_t process_umask() {
    static const mode_t mask = [] {
        const mode_t m = ::umask(022);
        ::umask(m);
        return m;
    }();
    return mask;
}

}  // namespace

InputFile::InputFile(const std::string& path, const std::string& what) {
    // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused below.
    fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw IoError(fmt::format("cannot read {} '{}': {}", what, path, reason(errno)));
    struct stat st {};
    const int err = ::fstat(fd, &st) != 0 ? errno : 0;
    if (err != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        if (err != 0) throw IoError(fmt::format("cannot read {} '{}': {}", what, path, reason(err)));
        throw IoError(fmt::format("cannot read {} '{}': it is {}, not a regular file", what, path,
                                  kind_of(st.st_mode)));
    }
    size = std::uint64_t(st.st_size);
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
}

InputFile::~InputFile() { ::close(fd); }

std::string read_file_bounded(const std::string& path, std::size_t max_bytes, const std::string& what) {
    const InputFile file(path, what);
    const int fd = file.fd;
    if (file.size > max_bytes)
        throw IoError(
            fmt::format("cannot read {} '{}': it is {} bytes, more than the limit of {} bytes ({} MiB)", what,
                        path, file.size, max_bytes, max_bytes >> 20));
    std::string data;
    data.resize(std::size_t(file.size));
    std::size_t got = 0;
    // Reads at most max_bytes + 1 bytes whatever the size said (a file that grows).
    while (true) {
        if (got == data.size()) {
            if (data.size() > max_bytes) break;
            data.resize(std::min(max_bytes + 1, std::max<std::size_t>(4096, data.size() * 2)));
        }
        const ssize_t n = ::read(fd, data.data() + got, data.size() - got);
        if (n < 0) {
            if (errno == EINTR) continue;
            throw IoError(fmt::format("cannot read {} '{}': {}", what, path, reason(errno)));
        }
        if (n == 0) break;
        got += std::size_t(n);
    }
    if (got > max_bytes)
        throw IoError(fmt::format("cannot read {} '{}': it is larger than the limit of {} bytes ({} MiB)",
                                  what, path, max_bytes, max_bytes >> 20));
    data.resize(got);
    return data;
}

fs::path resolve_output_path(const std::string& path, bool overwrite) {
    if (path.empty()) throw IoError("cannot write '': the output path is empty");
    std::error_code ec;
    fs::path p = fs::absolute(fs::path(path), ec);
    if (ec) throw IoError(fmt::format("cannot write '{}': {}", path, ec.message()));
    // Follow symlinks to the file they name (written in place of it; the link stays).
    for (int hops = 0;; ++hops) {
        struct stat st {};
        if (::lstat(p.c_str(), &st) != 0) {
            if (errno != ENOENT) throw IoError(fmt::format("cannot write '{}': {}", path, reason(errno)));
            break;  // a new file
        }
        if (S_ISLNK(st.st_mode)) {
            if (hops >= 40)
                throw IoError(fmt::format("cannot write '{}': too many levels of symbolic links", path));
            const fs::path link = fs::read_symlink(p, ec);
            if (ec) throw IoError(fmt::format("cannot write '{}': {}", path, ec.message()));
            p = (link.is_absolute() ? link : p.parent_path() / link).lexically_normal();
            continue;
        }
        if (!S_ISREG(st.st_mode))
            throw NotRegularFile(fmt::format("cannot write '{}': it is {}; Welkin writes regular files only",
                                             path, kind_of(st.st_mode)));
        if (!overwrite)
            throw IoError(fmt::format("'{}' exists; refusing to overwrite it (pass overwrite)", path));
        break;
    }
    const fs::path dir = p.parent_path();
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        throw IoError(fmt::format("cannot write '{}': directory '{}' does not exist", path, dir.string()));
    return p;
}

TemporaryFile::TemporaryFile(const fs::path& target, const std::string& path) : target_(target), name_(path) {
    std::string name = target.filename().string();
    name.insert(0, 1, '.');
    name.append(".welkin-XXXXXX");
    std::string pattern = (target.parent_path() / name).string();
    fd_ = ::mkostemp(pattern.data(), O_CLOEXEC);
    if (fd_ < 0)
        throw IoError(fmt::format("cannot write '{}': cannot create a temporary file in '{}': {}", path,
                                  target.parent_path().string(), reason(errno)));
    tmp_ = pattern;
    slot_ = register_temporary(tmp_);
    // The mode a new file would get (or the replaced file's own), not mkstemp's 0600.
    struct stat st {};
    const mode_t mode = ::stat(target.c_str(), &st) == 0 && S_ISREG(st.st_mode) ? (st.st_mode & 07777)
                                                                                : (0666 & ~process_umask());
    ::fchmod(fd_, mode);
}

TemporaryFile::~TemporaryFile() { discard(); }

void TemporaryFile::close_fd() {
    if (fd_ >= 0) {
        const int fd = fd_;
        fd_ = -1;
        if (::close(fd) != 0 && errno != EINTR) {
            const int err = errno;
            discard();
            throw IoError(fmt::format("cannot write '{}': {}", name_, reason(err)));
        }
    }
}

void TemporaryFile::write_all(const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd_, p, size);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            discard();
            throw IoError(fmt::format("cannot write '{}': {}", name_, reason(err)));
        }
        p += n;
        size -= std::size_t(n);
    }
    if (::fsync(fd_) != 0 && errno != EINVAL && errno != EROFS) {
        const int err = errno;
        discard();
        throw IoError(fmt::format("cannot write '{}': {}", name_, reason(err)));
    }
    close_fd();
}

void TemporaryFile::commit(bool overwrite) {
    close_fd();
    if (done_) throw IoError(fmt::format("cannot write '{}': the temporary file is gone", name_));
    // The target may have changed since it was resolved: never replace a special file.
    struct stat st {};
    if (::lstat(target_.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
        discard();
        throw NotRegularFile(fmt::format("cannot write '{}': it is {}; Welkin writes regular files only",
                                         name_, kind_of(st.st_mode)));
    }
    if (overwrite) {
        if (::rename(tmp_.c_str(), target_.c_str()) != 0) {
            const int err = errno;
            discard();
            throw IoError(fmt::format("cannot write '{}': {}", name_, reason(err)));
        }
    } else if (::link(tmp_.c_str(), target_.c_str()) == 0) {
        ::unlink(tmp_.c_str());  // the link holds the data now
    } else {
        const int err = errno;
        if (err == EEXIST) {
            discard();
            throw IoError(fmt::format("'{}' exists; refusing to overwrite it (pass overwrite)", name_));
        }
        // No hard links on this file system: check, then rename (a small window).
        if (::lstat(target_.c_str(), &st) == 0) {
            discard();
            throw IoError(fmt::format("'{}' exists; refusing to overwrite it (pass overwrite)", name_));
        }
        if (::rename(tmp_.c_str(), target_.c_str()) != 0) {
            const int err2 = errno;
            discard();
            throw IoError(fmt::format("cannot write '{}': {}", name_, reason(err2)));
        }
    }
    done_ = true;
    unregister_temporary(slot_);
    slot_ = -1;
}

void TemporaryFile::discard() noexcept {
    if (fd_ >= 0) {
        ::close(fd_);
        fd_ = -1;
    }
    if (!done_ && !tmp_.empty()) ::unlink(tmp_.c_str());
    done_ = true;
    unregister_temporary(slot_);
    slot_ = -1;
}

void write_file_atomic(const std::string& path, const std::string& text, bool overwrite) {
    const fs::path target = resolve_output_path(path, overwrite);
    TemporaryFile tmp(target, path);
    tmp.write_all(text.data(), text.size());
    tmp.commit(overwrite);
}

void remove_temporaries_signal_safe() noexcept {
    for (Slot& s : g_slots)
        if (s.used.load()) ::unlink(s.path.data());
}

}  // namespace welkin
