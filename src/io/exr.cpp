// OpenEXR reading and atomic writing; see exr_io.hpp.
#include "welkin/io/exr.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <set>
#include <system_error>

#include <Iex.h>
#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <fmt/format.h>
#include <half.h>
#include <unistd.h>

#include "welkin/base/error.hpp"
#include "welkin/io/file.hpp"

namespace welkin {
namespace {

namespace fs = std::filesystem;

// Largest finite half: (2 - 2^-10) * 2^15.
constexpr float kHalfMax = 65504.0f;

void check_image(const ExrImage& image) {
    if (image.width < 1 || image.height < 1)
        throw InvalidArgument(
            "image", fmt::format("size must be at least 1 x 1, got {} x {}", image.width, image.height));
    if (image.channel_names.empty())
        throw InvalidArgument("image.channel_names", "needs at least one channel");
    std::set<std::string> seen;
    for (const std::string& name : image.channel_names) {
        if (name.empty()) throw InvalidArgument("image.channel_names", "empty channel name");
        if (!seen.insert(name).second)
            throw InvalidArgument("image.channel_names", fmt::format("duplicate channel name '{}'", name));
    }
    const std::size_t expected = std::size_t(image.width) * std::size_t(image.height) * image.channels();
    if (image.pixels.size() != expected)
        throw InvalidArgument("image.pixels",
                              fmt::format("needs width * height * channels = {} values, got {}", expected,
                                          image.pixels.size()));
}

}  // namespace

int ExrImage::channel_index(const std::string& name) const {
    const auto it = std::find(channel_names.begin(), channel_names.end(), name);
    return it == channel_names.end() ? -1 : int(it - channel_names.begin());
}

ExrWriteReport write_exr(const std::string& path, const ExrImage& image, const ExrWriteOptions& options) {
    check_image(image);
    // Symlinks followed; a directory, device, FIFO or socket refused; an existing file
    // refused unless overwrite.
    const fs::path target = resolve_output_path(path, options.overwrite);
    if (options.cancelled && options.cancelled()) throw Cancelled();

    // Half files: clamp what half cannot hold (finite values beyond +-65504 would become
    // infinities), then round to half (OpenEXR's writer wants the buffer in the file's
    // pixel type).
    ExrWriteReport report;
    const bool half = options.pixel_type == ExrPixelType::Half;
    std::vector<Imath::half> halves;
    if (half) {
        halves.resize(image.pixels.size());
        for (std::size_t k = 0; k < image.pixels.size(); ++k) {
            float v = image.pixels[k];
            if (std::isfinite(v) && std::abs(v) > kHalfMax) {
                v = std::copysign(kHalfMax, v);
                ++report.clamped_values;
            }
            halves[k] = Imath::half(v);
        }
    }
    const char* data = half ? reinterpret_cast<const char*>(halves.data())
                            : reinterpret_cast<const char*>(image.pixels.data());
    const std::size_t value_size = half ? sizeof(Imath::half) : sizeof(float);
    const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
    const std::size_t nc = image.channels();
    TemporaryFile tmp(target, path);
    tmp.close_fd();  // OpenEXR opens it by name
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const auto& [key, value] : options.attributes) header.insert(key, Imf::StringAttribute(value));
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < nc; ++c) {
            header.channels().insert(image.channel_names[c], Imf::Channel(type));
            // OpenEXR's y grows downwards from the data window's top: row 0 is the top.
            fb.insert(image.channel_names[c],
                      Imf::Slice(type, const_cast<char*>(data + value_size * c), value_size * nc,
                                 value_size * nc * std::size_t(image.width)));
        }
        Imf::OutputFile file(tmp.path().c_str(), header);
        file.setFrameBuffer(fb);
        // In bands, so that a cancellation (Ctrl-C at the CLI) is seen during a long write.
        constexpr int kBand = 64;
        for (int y = 0; y < image.height; y += kBand) {
            if (options.cancelled && options.cancelled()) throw Cancelled();
            file.writePixels(std::min(kBand, image.height - y));
        }
    } catch (const Cancelled&) {
        tmp.discard();
        throw;
    } catch (const std::bad_alloc&) {
        tmp.discard();
        throw OutOfMemory(fmt::format("cannot write '{}': out of memory", path));
    } catch (const std::exception& e) {
        tmp.discard();
        throw IoError(fmt::format("cannot write '{}': {}", path, e.what()));
    }
    if (options.cancelled && options.cancelled()) throw Cancelled();  // ~TemporaryFile removes it
    tmp.commit(options.overwrite);
    return report;
}

ExrImage read_exr(const std::string& path) {
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        ExrImage image;
        image.width = dw.max.x - dw.min.x + 1;
        image.height = dw.max.y - dw.min.y + 1;
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                throw IoError(fmt::format("cannot read '{}': channel '{}' is subsampled", path, it.name()));
            image.channel_names.push_back(it.name());
        }
        const std::size_t nc = image.channels();
        image.pixels.assign(std::size_t(image.width) * std::size_t(image.height) * nc, 0.0f);
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < nc; ++c)
            fb.insert(image.channel_names[c],
                      Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, dw, sizeof(float) * nc,
                                       sizeof(float) * nc * std::size_t(image.width)));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return image;
    } catch (const IoError&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(fmt::format("cannot read '{}': {}", path, e.what()));
    }
}

ExrHeaderInfo read_exr_header(const std::string& path) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        ExrHeaderInfo info;
        info.width = dw.max.x - dw.min.x + 1;
        info.height = dw.max.y - dw.min.y + 1;
        for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
            info.channel_names.push_back(it.name());
        return info;
    } catch (const std::exception& e) {
        throw IoError(fmt::format("cannot read '{}': {}", path, e.what()));
    }
}

ExrImage read_exr_channels(const std::string& path, const std::vector<std::string>& names) {
    ExrImage image;
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        for (const std::string& name : names) {
            const Imf::Channel* channel = header.channels().findChannel(name);
            if (!channel)
                throw InvalidArgument("channel", fmt::format("'{}' has no channel '{}'", path, name));
            if (channel->xSampling != 1 || channel->ySampling != 1)
                throw IoError(fmt::format("cannot read '{}': channel '{}' is subsampled", path, name));
        }
        const Imath::Box2i dw = header.dataWindow();
        image.width = dw.max.x - dw.min.x + 1;
        image.height = dw.max.y - dw.min.y + 1;
        image.channel_names = names;
        const std::size_t nc = names.size();
        image.pixels.assign(std::size_t(image.width) * std::size_t(image.height) * nc, 0.0f);
        Imf::FrameBuffer fb;
        for (std::size_t c = 0; c < nc; ++c)
            fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, dw, sizeof(float) * nc,
                                                 sizeof(float) * nc * std::size_t(image.width)));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
    } catch (const InvalidArgument&) {
        throw;
    } catch (const IoError&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(fmt::format("cannot read '{}': {}", path, e.what()));
    }
    return image;
}

void set_exr_thread_count(int threads) {
    require_in_range("threads", threads, 0, 1024);
    Imf::setGlobalThreadCount(threads);
}

}  // namespace welkin
