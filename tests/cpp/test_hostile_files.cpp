// SPDX-License-Identifier: Apache-2.0
// Hostile files and unbounded settings: a corrupt VDB whose tree overwrites the heap of the
// process that parses it, an EXR input that is a FIFO or declares an absurd size, a wind
// offset beyond the noise's resolution; and the defaults a user expects (a camera without a
// type, a camera that sees 100 m).
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <sys/stat.h>
#include <unistd.h>

#include "welkin/aerial/aerial_table.hpp"
#include "welkin/base/error.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/vdb.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
namespace fs = std::filesystem;

namespace {

const fs::path kVdbCorpus = fs::path(WELKIN_TEST_DATA_DIR) / ".." / "fuzz" / "corpus" / "vdb";

template <class F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class HostileFiles : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("welkin_hostile_files_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
};

}  // namespace

// Three byte-flipped copies of a ball VDB: OpenVDB 10's io::bloscFromStream copies a chunk
// of the declared length into a 336- or 800-byte buffer (the rest of the file), then throws.
// The reader child reports the exception (or dies of the overwrite, as the heap's layout
// has it); the host, which parses only what the child wrote back, refuses the file and its
// heap stays sound. Before, the host parsed the file's tree
// itself after the child's exception, and died later (glibc: "double free or corruption",
// or a segfault at exit).
TEST_F(HostileFiles, VdbWhoseTreeOverwritesTheHeapThenThrowsLeavesTheHostSound) {
    for (const char* name : {"crash_ball_15.vdb", "crash_ball_36.vdb", "crash_ball_97.vdb"}) {
        const std::string file = (kVdbCorpus / name).string();
        ASSERT_TRUE(fs::exists(file)) << file;
        for (int attempt = 0; attempt < 3; ++attempt) {
            const std::string message = error_of([&] { VdbClouds clouds(file, {}); });
            EXPECT_TRUE(contains(message, file)) << message;
            EXPECT_TRUE(contains(message, "corrupt data")) << message;
            // The child threw (OpenVDB's "Expected to read a 336-byte uncompressed chunk ..."),
            // or glibc caught the overwrite first and aborted it: either way it only refused.
            EXPECT_TRUE(contains(message, "reader process")) << message;
        }
    }
    // glibc checks its heap's bookkeeping as blocks are freed and reused: an overwrite left
    // behind in this process ends it here.
    std::vector<std::unique_ptr<char[]>> blocks;
    for (int i = 0; i < 20000; ++i) {
        blocks.emplace_back(new char[std::size_t(16 + (i * 37) % 4000)]);
        std::memset(blocks.back().get(), i & 0xff, 16);
    }
    for (std::size_t i = 0; i < blocks.size(); i += 2) blocks[i].reset();
    blocks.clear();
}

// The host reads the grid from the child's stream: the same grid as the file's, voxel for
// voxel (OpenVDB reads the original file here, in the test, as the reference).
TEST_F(HostileFiles, VdbGridReadBackFromTheReaderEqualsTheFilesGrid) {
    const std::string file = (kVdbCorpus / "ball.vdb").string();
    openvdb::initialize();
    openvdb::io::File f(file);
    f.open();
    const auto ref = openvdb::gridPtrCast<openvdb::FloatGrid>(f.readGrid("density"));
    f.close();
    ASSERT_TRUE(ref);
    VdbCloudOptions o;
    o.placement = VdbCloudOptions::VoxelPlacement::OpenVdb;  // voxel ijk at index point ijk
    o.density_scale = 2.0;
    const VdbClouds clouds(file, o);
    EXPECT_EQ(clouds.active_voxel_count(), ref->activeVoxelCount());
    float max_value = 0.0f;
    std::size_t checked = 0;
    for (auto it = ref->cbeginValueOn(); it; ++it) {
        if (!it.isVoxelValue()) continue;
        max_value = std::max(max_value, *it);
        if (++checked % 7 != 0) continue;  // every 7th voxel: the centre of a voxel reads its value
        const openvdb::Vec3d w = ref->transform().indexToWorld(it.getCoord());
        EXPECT_NEAR(clouds.sigma_t({w.x(), w.y(), w.z()}), 2.0 * double(*it), 1e-6 * (1.0 + *it))
            << it.getCoord();
    }
    EXPECT_GT(checked, 100u);
    EXPECT_EQ(clouds.max_value(), double(max_value));
}

// A FIFO given as an EXR input is refused at once (opening it used to wait for a writer
// for ever), in each of the ways an EXR is read; so are a directory and a device.
TEST_F(HostileFiles, ExrReadersRefuseAFifoADirectoryAndADeviceAtOnce) {
    ASSERT_EQ(::mkfifo(path("f.exr").c_str(), 0644), 0);
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_TRUE(contains(error_of([&] { read_exr(path("f.exr")); }), "FIFO"));
    EXPECT_TRUE(contains(error_of([&] { read_exr_header(path("f.exr")); }), "FIFO"));
    EXPECT_TRUE(contains(error_of([&] { read_exr_channels(path("f.exr"), {"Z"}); }), "FIFO"));
    EXPECT_THROW(read_exr(path("f.exr")), IoError);
    EXPECT_TRUE(contains(error_of([&] { read_exr(dir_.string()); }), "directory"));
    EXPECT_TRUE(contains(error_of([] { read_exr("/dev/zero"); }), "character device"));
    EXPECT_TRUE(contains(error_of([&] { read_exr(path("missing.exr")); }), "missing.exr"));
    EXPECT_LT(seconds_since(t0), 5.0);
}

// A header that claims 100000 x 100000 pixels (a few bytes changed in a 4 x 3 image; it
// used to end in a bare std::bad_alloc, OSError in Python):
// OutOfMemory naming the file and what it would need, before anything that size is
// allocated; the header itself still reads.
TEST_F(HostileFiles, ExrWithAnAbsurdDataWindowIsOutOfMemoryBeforeAllocating) {
    ExrImage im;
    im.width = 4;
    im.height = 3;
    im.channel_names = {"R", "G", "B"};
    im.pixels.assign(4 * 3 * 3, 0.25f);
    write_exr(path("small.exr"), im);
    std::string bytes;
    {
        std::ifstream in(path("small.exr"), std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::string key("dataWindow\0box2i\0", 17);
    const std::size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const std::int32_t window[4] = {0, 0, 99999, 99999};  // xmin, ymin, xmax, ymax
    std::memcpy(bytes.data() + at + key.size() + 4, window, sizeof window);
    // As it is, the file cannot hold the chunk offset table such a header needs (6250 entries
    // of 8 bytes for 100000 lines in chunks of 16): refused before OpenEXR allocates it.
    std::ofstream(path("short.exr"), std::ios::binary) << bytes;
    const std::string short_error = error_of([&] { read_exr_header(path("short.exr")); });
    EXPECT_TRUE(contains(short_error, "at least 6250 chunks")) << short_error;
    EXPECT_TRUE(contains(short_error, path("short.exr"))) << short_error;
    // With room for the table, OpenEXR opens it.
    bytes.append(std::size_t(64) << 10, '\0');
    std::ofstream(path("huge.exr"), std::ios::binary) << bytes;

    EXPECT_EQ(read_exr_header(path("huge.exr")).width, 100000);
    const auto t0 = std::chrono::steady_clock::now();
    std::string what;
    try {
        read_exr(path("huge.exr"));
        ADD_FAILURE() << "read an image of 1e10 pixels";
    } catch (const OutOfMemory& e) {
        what = e.what();
    }
    EXPECT_TRUE(contains(what, path("huge.exr"))) << what;
    EXPECT_TRUE(contains(what, "100000 x 100000")) << what;
    EXPECT_TRUE(contains(what, "GiB")) << what;
    EXPECT_THROW(read_exr_channels(path("huge.exr"), {"G"}), OutOfMemory);
    EXPECT_LT(seconds_since(t0), 5.0);
}

// The wind offset is bounded as evolution_m is: at 1e20 m every point of the field read one
// texel and the layer vanished while covered_fraction() still reported its coverage. At the
// bound the field is as cloudy as at home: the share of the area under cloud, measured on
// random columns of the test's own over 300 km (vertical optical depth >= 0.3 through
// sigma_t on the curved shell), is the setting's, 0.4, within 0.1, at home and at the bound.
TEST(WindOffset, IsBoundedAndTheLayerKeepsItsCloudsAtTheBound) {
    for (double w : {1.0000001e9, -2e9, 1e20, 1e300, HUGE_VAL, std::nan("")}) {
        CloudLayerParams p;
        p.wind_offset_m = {0.0, w};
        EXPECT_EQ(test::parameter_of([&] { p.validate(); }), "wind_offset_m[1]") << w;
        p.wind_offset_m = {w, 0.0};
        EXPECT_EQ(test::parameter_of([&] { p.validate(); }), "wind_offset_m[0]") << w;
    }
    const auto cloudy_share = [](glm::dvec2 wind) {
        CloudLayerParams p;  // cumulus, coverage 0.4 of the area
        p.coverage_measure = CloudCoverageMeasure::area;
        p.wind_offset_m = wind;
        const ProceduralClouds layer(p);
        const double R = p.planet_radius_m;
        std::mt19937_64 gen(3);
        std::uniform_real_distribution<double> U(-150e3, 150e3);
        constexpr int kColumns = 400, kSteps = 32;
        const double dh = (p.top_altitude_m - p.bottom_altitude_m) / kSteps;
        int cloudy = 0;
        for (int i = 0; i < kColumns; ++i) {
            const glm::dvec3 up = glm::normalize(glm::dvec3(U(gen), U(gen), R));
            double tau = 0.0;
            for (int k = 0; k < kSteps; ++k)
                tau += layer.sigma_t(glm::dvec3(0.0, 0.0, -R) +
                                     (R + p.bottom_altitude_m + (k + 0.5) * dh) * up) *
                       dh;
            cloudy += tau >= ProceduralClouds::kCoverageOpticalDepth;
        }
        return double(cloudy) / kColumns;
    };
    const double home = cloudy_share({0.0, 0.0}), far = cloudy_share({1e9, -1e9});
    EXPECT_NEAR(home, 0.4, 0.1);
    EXPECT_NEAR(far, 0.4, 0.1);
    EXPECT_NEAR(far, home, 0.1);
    const std::string json = R"({"version": 1, "clouds": {"layers": [{"wind_offset_m": [1e20, 0]}]}})";
    EXPECT_TRUE(
        contains(test::parameter_of([&] { SceneDescription::from_json_string(json); }), "wind_offset_m[0]"));
}

// A scene JSON camera without "type" is Blender's default camera, a perspective one, as
// docs/pipelines.md documents; its matrix_world is required.
TEST(SceneCamera, TypeDefaultsToPerspectiveAndMatrixWorldIsRequired) {
    const std::string m = R"("matrix_world": [[1,0,0,0],[0,1,0,0],[0,0,1,5],[0,0,0,1]])";
    const SceneDescription plain =
        SceneDescription::from_json_string(R"({"version": 1, "camera": {)" + m + "}}");
    const SceneDescription persp =
        SceneDescription::from_json_string(R"({"version": 1, "camera": {"type": "PERSP", )" + m + "}}");
    ASSERT_TRUE(plain.camera.has_value());
    EXPECT_EQ(plain.camera->type, CameraType::Perspective);
    EXPECT_EQ(plain.to_json_string(), persp.to_json_string());
    EXPECT_EQ(test::parameter_of([] {
                  SceneDescription::from_json_string(R"({"version": 1, "camera": {"type": "PERSP"}})");
              }),
              "camera.matrix_world");
    EXPECT_EQ(
        test::parameter_of([&] {
            SceneDescription::from_json_string(R"({"version": 1, "camera": {"type": "FISHEYE", )" + m + "}}");
        }),
        "camera.type");
}

// Blender's default camera sees 100 m (Clip End): the direction table's last slice is then
// at 100 m, under two linear distances (200 m); the slices follow the documented mapping
// d_k = d_0 (e^(k c) - 1), c = ln(1 + d_max / d_0) / (slices - 1), nearly evenly spaced.
TEST(AerialTableLayout, AShortClipEndIsAcceptedAndKeepsTheDocumentedSlices) {
    AerialTableLayout layout;
    layout.max_distance_m = 100.0;
    EXPECT_NO_THROW(layout.validate());
    EXPECT_NEAR(layout.slice_distance(layout.slices - 1), 100.0, 1e-9);
    EXPECT_EQ(layout.slice_distance(0), 0.0);
    const double c = std::log(2.0) / (layout.slices - 1);
    for (int k = 1; k < layout.slices; ++k) {
        EXPECT_NEAR(layout.slice_distance(k), 100.0 * std::expm1(k * c), 1e-9) << k;
        EXPECT_GT(layout.slice_distance(k), layout.slice_distance(k - 1));
    }
    // Evenly spaced within a factor e^c ~ 1.015 from one slice to the next.
    const double first = layout.slice_distance(1), last = 100.0 - layout.slice_distance(layout.slices - 2);
    EXPECT_LT(last / first, 2.0);
    layout.max_distance_m = 1e-4;
    EXPECT_EQ(test::parameter_of([&] { layout.validate(); }), "table.max_distance_m");
}
