// SPDX-License-Identifier: Apache-2.0
// OpenEXR reading and atomic writing; see io/exr.hpp.
#include "welkin/io/exr.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <system_error>

#include <Iex.h>
#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <ImfTileDescription.h>
#include <ImfVersion.h>
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

namespace {

// The file through an InputFile (io/file.hpp): a FIFO, device or directory is refused at
// once instead of OpenEXR's blocking open, and OpenEXR reads the very file that was checked.
class InputFileStream : public Imf::IStream {
public:
    explicit InputFileStream(const std::string& path) : Imf::IStream(path.c_str()), file_(path, "EXR file") {}
    bool read(char c[], int n) override {
        if (n < 0 || pos_ + std::uint64_t(n) > file_.size) throw Iex::InputExc("Unexpected end of file.");
        for (int done = 0; done < n;) {
            const ssize_t got = ::pread(file_.fd, c + done, std::size_t(n - done), off_t(pos_ + done));
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) throw Iex::InputExc(std::strerror(errno));
            if (got == 0) throw Iex::InputExc("Unexpected end of file.");
            done += int(got);
        }
        pos_ += std::uint64_t(n);
        return pos_ < file_.size;
    }
    std::uint64_t tellg() override { return pos_; }
    void seekg(std::uint64_t pos) override { pos_ = pos; }
    std::uint64_t size() const { return file_.size; }

private:
    InputFile file_;
    std::uint64_t pos_ = 0;
};

// Scan lines per chunk of a scan-line part (OpenEXR's file layout, one per compression).
std::uint64_t lines_per_chunk(Imf::Compression c) {
    switch (c) {
        case Imf::ZIP_COMPRESSION:
        case Imf::PXR24_COMPRESSION:
            return 16;
        case Imf::PIZ_COMPRESSION:
        case Imf::B44_COMPRESSION:
        case Imf::B44A_COMPRESSION:
        case Imf::DWAA_COMPRESSION:
            return 32;
        case Imf::DWAB_COMPRESSION:
            return 256;
        default:
            return 1;
    }
}

// The fewest chunks a part with this header has (a tiled part: its full-resolution level).
std::uint64_t fewest_chunks(const Imf::Header& h) {
    const Imath::Box2i& dw = h.dataWindow();
    const std::uint64_t w = std::uint64_t(std::max<std::int64_t>(0, std::int64_t(dw.max.x) - dw.min.x + 1));
    const std::uint64_t ht = std::uint64_t(std::max<std::int64_t>(0, std::int64_t(dw.max.y) - dw.min.y + 1));
    if (h.hasTileDescription()) {
        const std::uint64_t tx = std::max(1u, h.tileDescription().xSize);
        const std::uint64_t ty = std::max(1u, h.tileDescription().ySize);
        return ((w + tx - 1) / tx) * ((ht + ty - 1) / ty);
    }
    const std::uint64_t n = lines_per_chunk(h.compression());
    return (ht + n - 1) / n;
}

// A null-terminated name of a header (OpenEXR's names are at most 255 bytes).
std::string read_name(Imf::IStream& in) {
    std::string name;
    for (char c = 1; name.size() <= 256;) {
        in.read(&c, 1);
        if (c == 0) return name;
        name.push_back(c);
    }
    throw Iex::InputExc("a header attribute's name or type is longer than 255 bytes");
}

// Walks one header's attributes (name, type, byte count, value) and checks that every
// value fits in what is left of the file: OpenEXR sizes an attribute's storage from its
// byte count before reading it (a string of 700 MB declared in a 364-byte file). Leaves
// `in` where it was.
void check_attribute_sizes(const std::string& path, Imf::IStream& in, std::uint64_t file_size) {
    const std::uint64_t start = in.tellg();
    for (std::string name = read_name(in); !name.empty(); name = read_name(in)) {
        (void)read_name(in);  // the type
        unsigned char b[4];
        in.read(reinterpret_cast<char*>(b), 4);
        const std::int32_t size = std::int32_t(b[0] | (b[1] << 8) | (b[2] << 16) | (unsigned(b[3]) << 24));
        const std::uint64_t at = in.tellg();
        if (size < 0 || std::uint64_t(size) > file_size - std::min(at, file_size))
            throw IoError(
                fmt::format("cannot read '{}': its header attribute '{}' declares {} bytes, more "
                            "than the {} left in the file: a corrupt or truncated file",
                            path, name, size, file_size - std::min(at, file_size)));
        in.seekg(at + std::uint64_t(size));
    }
    in.seekg(start);
}

// Before OpenEXR sizes anything from a header: every part's chunk offset table (8 bytes a
// chunk, stored in the file after the headers) must fit in the file. OpenEXR allocates
// and clears that table from the data window as it opens a file (2^31 lines without
// compression: 16 GiB). Headers OpenEXR cannot parse are left to its own error. Leaves
// `in` at the start of the file.
void check_chunk_tables(const std::string& path, Imf::IStream& in, std::uint64_t file_size) {
    char magic[4];
    in.read(magic, 4);
    if (!Imf::isImfMagic(magic)) {
        in.seekg(0);
        return;
    }
    unsigned char v[4];
    in.read(reinterpret_cast<char*>(v), 4);
    int version = int(v[0] | (v[1] << 8) | (v[2] << 16) | (unsigned(v[3]) << 24));
    const bool multi = Imf::isMultiPart(version);
    std::uint64_t chunks = 0;
    for (int part = 0; part < 1 << 16; ++part) {
        if (multi) {
            const std::uint64_t at = in.tellg();
            char next = 0;
            in.read(&next, 1);
            if (next == 0) break;  // the empty header that ends a multi-part file's list
            in.seekg(at);
        }
        check_attribute_sizes(path, in, file_size);
        Imf::Header header;
        header.readFrom(in, version);
        chunks += fewest_chunks(header);
        if (chunks > file_size / 8)
            throw IoError(
                fmt::format("cannot read '{}': its header declares at least {} chunks, whose offset "
                            "table alone ({} bytes) is larger than the file ({} bytes): a corrupt "
                            "or truncated file",
                            path, chunks, chunks * 8, file_size));
        if (!multi) break;
    }
    in.seekg(0);
}

// An image whose floats would take more than half of this machine's memory (a corrupt or
// hostile data window: 100000 x 100000 pixels in a file of a few bytes) is refused before
// its pixels are allocated: OutOfMemory (MemoryError in Python) naming the file.
void check_pixel_memory(const std::string& path, int width, int height, std::size_t channels) {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    const double physical = pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
    const double needed = double(width) * double(height) * double(channels) * double(sizeof(float));
    if (physical > 0.0 && needed > 0.5 * physical)
        throw OutOfMemory(
            fmt::format("cannot read '{}': its {} x {} pixels of {} channels need {:.1f} GiB as "
                        "float, more than half of this machine's {:.1f} GiB of memory",
                        path, width, height, channels, needed / double(1 << 30), physical / double(1 << 30)));
}

// One channel of a file: the part that holds it and its name there.
struct ChannelSource {
    int part = 0;
    std::string name_in_part;
};

// The channels of every part of a file, as read_exr names them. Blender 5.0 writes a
// multilayer EXR as a multi-part file, one part per pass, with full "<layer>.<pass>.<chan>"
// names in each part; single-part files are the common case. A name that occurs in more than
// one part (the views of a stereo file, say) is qualified with its part's name,
// "<part>.<channel>". Deep parts are refused; every part must share one data window.
struct FileChannels {
    Imath::Box2i data_window;
    std::vector<std::string> names;  // in the file's order, part by part
    std::vector<ChannelSource> sources;
};

FileChannels file_channels(const std::string& path, Imf::MultiPartInputFile& file) {
    FileChannels out;
    std::map<std::string, int> count;
    for (int p = 0; p < file.parts(); ++p)
        for (auto it = file.header(p).channels().begin(); it != file.header(p).channels().end(); ++it)
            ++count[it.name()];
    for (int p = 0; p < file.parts(); ++p) {
        const Imf::Header& header = file.header(p);
        if (header.hasType() && Imf::isDeepData(header.type()))
            throw IoError(fmt::format("cannot read '{}': part {} holds deep data", path, p));
        if (p == 0)
            out.data_window = header.dataWindow();
        else if (header.dataWindow() != out.data_window)
            throw IoError(
                fmt::format("cannot read '{}': part {} has another data window than part 0", path, p));
        const std::string part_name = header.hasName() ? header.name() : fmt::format("part{}", p);
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                throw IoError(fmt::format("cannot read '{}': channel '{}' is subsampled", path, it.name()));
            const std::string name = it.name();
            out.names.push_back(count[name] > 1 ? part_name + "." + name : name);
            out.sources.push_back({p, name});
        }
    }
    return out;
}

// Reads the channels `which` (indices into `channels`) into an interleaved float image.
ExrImage read_channels(const std::string& path, Imf::MultiPartInputFile& file, const FileChannels& channels,
                       const std::vector<std::size_t>& which) {
    const Imath::Box2i dw = channels.data_window;
    ExrImage image;
    image.width = dw.max.x - dw.min.x + 1;
    image.height = dw.max.y - dw.min.y + 1;
    const std::size_t nc = which.size();
    check_pixel_memory(path, image.width, image.height, nc);
    for (std::size_t k : which) image.channel_names.push_back(channels.names[k]);
    image.pixels.assign(std::size_t(image.width) * std::size_t(image.height) * nc, 0.0f);
    std::vector<Imf::FrameBuffer> buffers(std::size_t(file.parts()));
    for (std::size_t c = 0; c < nc; ++c) {
        const ChannelSource& source = channels.sources[which[c]];
        buffers[std::size_t(source.part)].insert(
            source.name_in_part, Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, dw, sizeof(float) * nc,
                                                  sizeof(float) * nc * std::size_t(image.width)));
    }
    for (int p = 0; p < file.parts(); ++p) {
        if (buffers[std::size_t(p)].begin() == buffers[std::size_t(p)].end()) continue;
        Imf::InputPart part(file, p);
        part.setFrameBuffer(buffers[std::size_t(p)]);
        part.readPixels(dw.min.y, dw.max.y);
    }
    return image;
}

// Runs `read` on the file opened through InputFileStream; OpenEXR's and the system's errors
// become IoError naming the file, running out of memory OutOfMemory naming it.
template <typename Read>
auto with_exr_file(const std::string& path, Read read) {
    try {
        InputFileStream stream(path);
        check_chunk_tables(path, stream, stream.size());
        Imf::MultiPartInputFile file(stream);
        return read(file, file_channels(path, file));
    } catch (const InvalidArgument&) {
        throw;
    } catch (const IoError&) {
        throw;
    } catch (const OutOfMemory&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw OutOfMemory(
            fmt::format("cannot read '{}': out of memory (a corrupt header, or an image "
                        "too large for this machine)",
                        path));
    } catch (const std::exception& e) {
        throw IoError(fmt::format("cannot read '{}': {}", path, e.what()));
    }
}

}  // namespace

ExrImage read_exr(const std::string& path) {
    return with_exr_file(path, [&](Imf::MultiPartInputFile& file, const FileChannels& channels) {
        std::vector<std::size_t> all(channels.names.size());
        for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
        return read_channels(path, file, channels, all);
    });
}

ExrHeaderInfo read_exr_header(const std::string& path) {
    return with_exr_file(path, [&](Imf::MultiPartInputFile&, const FileChannels& channels) {
        ExrHeaderInfo info;
        info.width = channels.data_window.max.x - channels.data_window.min.x + 1;
        info.height = channels.data_window.max.y - channels.data_window.min.y + 1;
        info.channel_names = channels.names;
        return info;
    });
}

ExrImage read_exr_channels(const std::string& path, const std::vector<std::string>& names) {
    return with_exr_file(path, [&](Imf::MultiPartInputFile& file, const FileChannels& channels) {
        std::vector<std::size_t> which;
        for (const std::string& name : names) {
            const auto it = std::find(channels.names.begin(), channels.names.end(), name);
            if (it == channels.names.end())
                throw InvalidArgument("channel", fmt::format("'{}' has no channel '{}'", path, name));
            which.push_back(std::size_t(it - channels.names.begin()));
        }
        return read_channels(path, file, channels, which);
    });
}

void set_exr_thread_count(int threads) {
    require_in_range("threads", threads, 0, 1024);
    Imf::setGlobalThreadCount(threads);
}

}  // namespace welkin
