// SPDX-License-Identifier: Apache-2.0
// OpenEXR images in and out: named float channels, top row first.
//
// The writer is atomic and careful with the user's files: it writes a temporary file in
// the target's directory and moves it into place only once it is complete, so a failed or
// cancelled write never leaves a partial image; it refuses to replace an existing file
// unless asked to. A symlink is written through; a directory, device, FIFO or socket is
// refused (io/file.hpp). Failures raise IoError naming the path.
//
// Channels are named as OpenEXR names them. A plain RGB image uses "R", "G", "B" (and
// "A"); a multilayer file, as Blender writes and reads them, names each channel
// "<layer>.<pass>.<channel>", e.g. "Welkin.Sky.R" (Blender splits at the dots: view layer
// "Welkin", pass "Sky", channel "R"). OpenEXR stores channels sorted by name; the reader
// returns them in the file's order, so look them up by name (channel_index). Multi-part
// files (Blender 5.0 writes one part per pass) read as one image with every part's channels;
// a name found in several parts is qualified as "<part name>.<channel>". All parts must
// share one data window; deep parts are refused.
//
// Half-float files hold magnitudes up to 65504: the writer clamps larger finite values to
// that (the sun's disc can exceed it) and reports how many it clamped.
//
// Thread-safety: the functions share no state; OpenEXR compresses on its own thread pool.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace welkin {

struct ExrImage {
    int width = 0, height = 0;
    std::vector<std::string> channel_names;
    std::vector<float> pixels;  // (height, width, channels) interleaved, top row first

    std::size_t channels() const { return channel_names.size(); }
    // Index of a channel, or -1 when absent.
    int channel_index(const std::string& name) const;
    float at(int x, int y, std::size_t channel) const {
        return pixels[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * channels() + channel];
    }
};

enum class ExrPixelType { Half, Float };

struct ExrWriteOptions {
    ExrPixelType pixel_type = ExrPixelType::Float;
    bool overwrite = false;
    // Extra string attributes for the header (e.g. "software", "comments").
    std::vector<std::pair<std::string, std::string>> attributes;
    // Asked between bands of rows while the file is written: true cancels the write (the
    // temporary file is removed, nothing is written) with welkin::Cancelled.
    std::function<bool()> cancelled;
};

struct ExrWriteReport {
    std::size_t clamped_values = 0;  // finite values beyond the half range, clamped
};

// Throws InvalidArgument for an inconsistent image (sizes, empty or duplicate channel
// names) and IoError naming `path` when the file exists (and !overwrite) or cannot be
// written.
ExrWriteReport write_exr(const std::string& path, const ExrImage& image, const ExrWriteOptions& options = {});

// Reading: `path` must be a regular file (a FIFO, device or directory is refused at once,
// io/file.hpp InputFile). An image whose float pixels would take more than half of this
// machine's memory (a corrupt or hostile data window) is refused before they are allocated,
// and running out of memory while reading is too: OutOfMemory naming `path` (MemoryError in
// Python).
//
// Reads every channel as float. Throws IoError naming `path` on failure.
ExrImage read_exr(const std::string& path);

// The size and channel names of an EXR file, from its header only (nothing is decoded).
struct ExrHeaderInfo {
    int width = 0, height = 0;
    std::vector<std::string> channel_names;
};
ExrHeaderInfo read_exr_header(const std::string& path);

// Reads only the named channels (in that order), as float; a multilayer render with many
// passes need not be decoded whole. Throws IoError naming `path` on failure, and
// InvalidArgument naming "channel" when one of them is absent.
ExrImage read_exr_channels(const std::string& path, const std::vector<std::string>& names);

// Threads OpenEXR uses to compress and decompress (its default is none: one thread does
// all the ZIP work). Process-wide (Imf::setGlobalThreadCount): for hosts that own the
// process, such as the CLI; a library embedding Welkin leaves it to its host.
void set_exr_thread_count(int threads);

}  // namespace welkin
