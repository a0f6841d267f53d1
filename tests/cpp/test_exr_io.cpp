// SPDX-License-Identifier: Apache-2.0
// EXR I/O: round trips (float, half, multilayer names), atomic and careful writing.
#include <cmath>
#include <filesystem>
#include <string>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "welkin/base/error.hpp"
#include "welkin/io/exr.hpp"

using namespace welkin;
namespace fs = std::filesystem;

namespace {

// A fresh, empty directory per test.
class ExrIo : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("welkin_exr_test_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    std::size_t files_in_dir() const {
        return std::size_t(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
    }
    fs::path dir_;
};

ExrImage gradient(int w, int h, std::vector<std::string> names) {
    ExrImage im;
    im.width = w;
    im.height = h;
    im.channel_names = std::move(names);
    im.pixels.resize(std::size_t(w) * h * im.channels());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (std::size_t c = 0; c < im.channels(); ++c)
                im.pixels[(std::size_t(y) * w + x) * im.channels() + c] =
                    float(0.001 * (x + 1) + 1.0 * y + 100.0 * c) * (c % 2 ? -1.0f : 1.0f);
    return im;
}

}  // namespace

TEST_F(ExrIo, FloatRoundTripIsExactAndTopRowFirst) {
    const ExrImage im = gradient(7, 5, {"R", "G", "B", "A"});
    write_exr(path("a.exr"), im);
    const ExrImage back = read_exr(path("a.exr"));
    ASSERT_EQ(back.width, 7);
    ASSERT_EQ(back.height, 5);
    ASSERT_EQ(back.channels(), 4u);
    for (const char* name : {"R", "G", "B", "A"}) {
        const int ci = back.channel_index(name), co = im.channel_index(name);
        ASSERT_GE(ci, 0) << name;
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 7; ++x) EXPECT_EQ(back.at(x, y, ci), im.at(x, y, co));
    }
    // Row 0 of the buffer is row 0 of the file (y grows downwards in OpenEXR).
    EXPECT_EQ(back.at(0, 0, back.channel_index("R")), im.pixels[0]);
    EXPECT_EQ(files_in_dir(), 1u);  // no temporary file left behind
}

TEST_F(ExrIo, HalfRoundTripWithinHalfPrecisionAndClampsOverflow) {
    ExrImage im = gradient(4, 3, {"Y"});
    im.pixels[0] = 1e6f;   // beyond half: clamped to 65504
    im.pixels[1] = -7e4f;  // likewise, negative
    im.pixels[2] = 3.14159f;
    ExrWriteOptions opt;
    opt.pixel_type = ExrPixelType::Half;
    const ExrWriteReport rep = write_exr(path("h.exr"), im, opt);
    EXPECT_EQ(rep.clamped_values, 2u);
    const ExrImage back = read_exr(path("h.exr"));
    EXPECT_EQ(back.pixels[0], 65504.0f);
    EXPECT_EQ(back.pixels[1], -65504.0f);
    for (std::size_t k = 2; k < im.pixels.size(); ++k)
        EXPECT_NEAR(back.pixels[k], im.pixels[k], std::abs(im.pixels[k]) * 1e-3 + 1e-7) << k;
}

TEST_F(ExrIo, MultilayerChannelNamesRoundTrip) {
    const ExrImage im =
        gradient(3, 2, {"Welkin.Sky.R", "Welkin.Sky.G", "Welkin.Sky.B", "Welkin.CloudDepth.Z"});
    ExrWriteOptions opt;
    opt.attributes = {{"software", "welkin test"}};
    write_exr(path("m.exr"), im, opt);
    const ExrImage back = read_exr(path("m.exr"));
    ASSERT_EQ(back.channels(), 4u);
    for (const std::string& name : im.channel_names) {
        const int ci = back.channel_index(name);
        ASSERT_GE(ci, 0) << name;
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 3; ++x) EXPECT_EQ(back.at(x, y, ci), im.at(x, y, im.channel_index(name)));
    }
    EXPECT_EQ(back.channel_index("R"), -1);
}

// Blender 5.0 writes a multilayer render as a multi-part file, one part per pass, each
// channel with its full name. Every part's channels read back as one image; a name that
// two parts share (a stereo file's views) is qualified with the part's name.
TEST_F(ExrIo, MultiPartFilesReadEveryPart) {
    const int w = 4, h = 3;
    struct Part {
        std::string name;
        std::vector<std::string> channels;
    };
    const std::vector<Part> parts = {{"ViewLayer.Combined", {"ViewLayer.Combined.R", "ViewLayer.Combined.A"}},
                                     {"ViewLayer.Depth", {"ViewLayer.Depth.Z"}},
                                     {"left", {"Y"}},
                                     {"right", {"Y"}}};
    std::vector<Imf::Header> headers;
    for (const Part& part : parts) {
        Imf::Header header(w, h);
        header.setName(part.name);
        header.setType(Imf::SCANLINEIMAGE);
        for (const std::string& c : part.channels) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
        headers.push_back(header);
    }
    // Value of channel c of part p at (x, y): unique, so a mix-up shows.
    auto value = [](std::size_t p, std::size_t c, int x, int y) {
        return float(1000 * p + 100 * c + 10 * y + x);
    };
    {
        Imf::MultiPartOutputFile file(path("multi.exr").c_str(), headers.data(), int(headers.size()));
        for (std::size_t p = 0; p < parts.size(); ++p) {
            const std::size_t nc = parts[p].channels.size();
            std::vector<float> pixels(std::size_t(w * h) * nc);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    for (std::size_t c = 0; c < nc; ++c)
                        pixels[(std::size_t(y * w + x)) * nc + c] = value(p, c, x, y);
            Imf::FrameBuffer fb;
            for (std::size_t c = 0; c < nc; ++c)
                fb.insert(parts[p].channels[c],
                          Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(pixels.data() + c),
                                     sizeof(float) * nc, sizeof(float) * nc * w));
            Imf::OutputPart out(file, int(p));
            out.setFrameBuffer(fb);
            out.writePixels(h);
        }
    }
    const ExrImage image = read_exr(path("multi.exr"));
    ASSERT_EQ(image.width, w);
    ASSERT_EQ(image.height, h);
    const std::vector<std::pair<std::string, std::pair<std::size_t, std::size_t>>> expected = {
        {"ViewLayer.Combined.R", {0, 0}},
        {"ViewLayer.Combined.A", {0, 1}},
        {"ViewLayer.Depth.Z", {1, 0}},
        {"left.Y", {2, 0}},
        {"right.Y", {3, 0}}};
    ASSERT_EQ(image.channels(), expected.size());
    for (const auto& [name, source] : expected) {
        const int ci = image.channel_index(name);
        ASSERT_GE(ci, 0) << name;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                EXPECT_EQ(image.at(x, y, std::size_t(ci)), value(source.first, source.second, x, y)) << name;
    }
    EXPECT_EQ(read_exr_header(path("multi.exr")).channel_names, image.channel_names);
    const ExrImage some = read_exr_channels(path("multi.exr"), {"right.Y", "ViewLayer.Depth.Z"});
    ASSERT_EQ(some.channels(), 2u);
    EXPECT_EQ(some.at(3, 2, 0), value(3, 0, 3, 2));
    EXPECT_EQ(some.at(3, 2, 1), value(1, 0, 3, 2));
    EXPECT_THROW(read_exr_channels(path("multi.exr"), {"Y"}), InvalidArgument);
}

TEST_F(ExrIo, RefusesToOverwriteUnlessAsked) {
    const std::string p = path("x.exr");
    const ExrImage first = gradient(2, 2, {"R"});
    ExrImage second = first;
    for (float& v : second.pixels) v += 1.0f;
    write_exr(p, first);
    try {
        write_exr(p, second);
        FAIL() << "overwrote an existing file";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
    EXPECT_EQ(read_exr(p).pixels, first.pixels);  // untouched
    ExrWriteOptions opt;
    opt.overwrite = true;
    write_exr(p, second, opt);
    EXPECT_EQ(read_exr(p).pixels, second.pixels);
    EXPECT_EQ(files_in_dir(), 1u);
}

TEST_F(ExrIo, UnwritablePlacesRaiseIoErrorNamingThePath) {
    const ExrImage im = gradient(2, 2, {"R"});
    // A directory that does not exist; a "directory" that is a file; a directory the
    // kernel will not let anyone create files in (even root); the target a directory.
    const std::string missing = path("no/such/dir/a.exr");
    fs::create_directories(dir_ / "sub");
    for (const std::string& p :
         {missing, std::string("/proc/welkin_test.exr"), path("file.exr") + "/a.exr", path("sub")}) {
        if (p == path("file.exr") + "/a.exr") write_exr(path("file.exr"), im);
        try {
            write_exr(p, im);
            FAIL() << "wrote " << p;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
        }
    }
    EXPECT_FALSE(fs::exists("/proc/welkin_test.exr"));
}

TEST_F(ExrIo, RejectsInconsistentImagesAndUnreadableFiles) {
    ExrImage im = gradient(2, 2, {"R", "G"});
    im.pixels.pop_back();
    EXPECT_THROW(write_exr(path("a.exr"), im), InvalidArgument);
    ExrImage dup = gradient(2, 2, {"R", "R"});
    EXPECT_THROW(write_exr(path("a.exr"), dup), InvalidArgument);
    ExrImage empty;
    EXPECT_THROW(write_exr(path("a.exr"), empty), InvalidArgument);
    EXPECT_EQ(files_in_dir(), 0u);
    EXPECT_THROW(read_exr(path("missing.exr")), IoError);
    {
        std::FILE* f = std::fopen(path("junk.exr").c_str(), "w");
        std::fputs("not an exr", f);
        std::fclose(f);
    }
    try {
        read_exr(path("junk.exr"));
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("junk.exr"), std::string::npos);
    }
}
