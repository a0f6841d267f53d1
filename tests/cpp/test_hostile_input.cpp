// SPDX-License-Identifier: Apache-2.0
// Hostile input and careful output (issue 18, items 4-7; issue 14): every writer writes
// through symlinks and refuses special files; every reader is bounded; JSON errors name
// the file, the key path and the failure; temporaries are unique and never left behind.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "cloud_test_util.hpp"
#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"
#include "welkin/clouds/vdb.hpp"
#include "welkin/io/exr.hpp"
#include "welkin/io/file.hpp"
#include "welkin/io/json.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
namespace fs = std::filesystem;

namespace {

class Hostile : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("welkin_hostile_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    std::vector<std::string> entries() const {
        std::vector<std::string> out;
        for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
        std::sort(out.begin(), out.end());
        return out;
    }
    void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
    std::string read(const std::string& name) const {
        std::ifstream in(path(name));
        return std::string(std::istreambuf_iterator<char>(in), {});
    }
    fs::path dir_;
};

ExrImage small_image() {
    ExrImage im;
    im.width = 4;
    im.height = 300;  // several bands of 64 rows
    im.channel_names = {"R", "G", "B"};
    im.pixels.assign(std::size_t(4) * 300 * 3, 0.5f);
    return im;
}

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

}  // namespace

// --- item 4: symlinks are written through, special files refused -----------------------

TEST_F(Hostile, EveryWriterWritesThroughASymlinkAndKeepsIt) {
    fs::create_directories(dir_ / "real");
    const Atmosphere atm = Atmosphere::preset("clear");
    SceneDescription scene;
    for (const std::string ext : {"exr", "atm.json", "scene.json"}) {
        const fs::path target = dir_ / "real" / ("out." + ext);
        std::ofstream(target) << "old";
        const std::string link = path("link." + ext);
        fs::create_symlink(fs::path("real") / ("out." + ext), link);
        if (ext == "exr") {
            ExrWriteOptions o;
            o.overwrite = true;
            write_exr(link, small_image(), o);
            EXPECT_EQ(read_exr(target.string()).height, 300);
        } else if (ext == "atm.json") {
            atm.to_json_file(link, true);
            EXPECT_EQ(Atmosphere::from_json_file(target.string()).name, atm.name);
        } else {
            scene.to_json_file(link, true);
            EXPECT_NO_THROW(SceneDescription::from_json_file(target.string()));
        }
        EXPECT_TRUE(fs::is_symlink(link)) << ext;
        // Without overwrite, the existing target is not replaced.
        EXPECT_TRUE(contains(error_of([&] { atm.to_json_file(link, false); }), "exists"));
    }
    EXPECT_EQ(fs::directory_iterator(dir_ / "real")->path().filename().string().substr(0, 4), "out.");
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_ / "real")) ++n;
    EXPECT_EQ(n, 3u);  // no temporaries left beside the targets
}

TEST_F(Hostile, EveryWriterRefusesADeviceFifoSocketOrDirectoryEvenWithOverwrite) {
    ASSERT_EQ(::mkfifo(path("fifo").c_str(), 0644), 0);
    fs::create_directories(dir_ / "adir");
    const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    const std::string sp = path("sock");
    ASSERT_LT(sp.size(), sizeof(addr.sun_path));
    std::strcpy(addr.sun_path, sp.c_str());
    ASSERT_EQ(::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
    fs::create_symlink(path("fifo"), path("link_to_fifo"));
    ExrWriteOptions o;
    o.overwrite = true;
    for (const std::string name : {"fifo", "adir", "sock", "link_to_fifo"}) {
        const std::string p = path(name);
        EXPECT_THROW(write_exr(p, small_image(), o), NotRegularFile) << name;
        EXPECT_THROW(Atmosphere::preset("clear").to_json_file(p, true), NotRegularFile) << name;
        EXPECT_THROW(SceneDescription{}.to_json_file(p, true), NotRegularFile) << name;
        EXPECT_TRUE(contains(error_of([&] { write_file_atomic(p, "x", true); }), p)) << name;
    }
    ::close(sock);
    EXPECT_TRUE(fs::is_fifo(path("fifo")));
    EXPECT_TRUE(fs::is_socket(path("sock")));
    EXPECT_TRUE(fs::is_directory(path("adir")));
    EXPECT_EQ(entries(), (std::vector<std::string>{"adir", "fifo", "link_to_fifo", "sock"}));
    // A character device: refused before anything is created (never replaced, as root too).
    EXPECT_THROW(resolve_output_path("/dev/null", true), NotRegularFile);
    EXPECT_TRUE(contains(error_of([] { resolve_output_path("/dev/null", true); }), "character device"));
}

// --- item 5: bounded reads, limits on counts and extents ---------------------------------

TEST_F(Hostile, ReadersRefuseDevicesFifosDirectoriesAndHugeFilesAtOnce) {
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_THROW(Atmosphere::from_json_file("/dev/zero"), IoError);
    EXPECT_TRUE(contains(error_of([] { Atmosphere::from_json_file("/dev/zero"); }), "character device"));
    EXPECT_THROW(SceneDescription::from_json_file("/dev/zero"), IoError);
    ASSERT_EQ(::mkfifo(path("fifo").c_str(), 0644), 0);  // no writer: opening must not block
    EXPECT_TRUE(contains(error_of([&] { Atmosphere::from_json_file(path("fifo")); }), "FIFO"));
    fs::create_directories(dir_ / "adir");
    EXPECT_TRUE(
        contains(error_of([&] { SceneDescription::from_json_file(path("adir")); }), "is a directory"));
    EXPECT_TRUE(contains(error_of([&] { Atmosphere::from_json_file(path("adir")); }), "is a directory"));
    // One byte over the limit (a sparse file: no disk used).
    { std::ofstream(path("big.json")) << ' '; }
    fs::resize_file(path("big.json"), kMaxJsonFileBytes + 1);
    EXPECT_TRUE(contains(error_of([&] { Atmosphere::from_json_file(path("big.json")); }), "limit"));
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}

TEST_F(Hostile, DensityLayerAndCloudLayerCountsAreLimitedAtValidation) {
    std::string layers;
    for (std::size_t i = 0; i <= DensityProfile::kMaxLayers; ++i)
        layers += std::string(i ? "," : "") + R"({"width_m": 1000, "constant": 1})";
    const std::string text = R"({"preset": "clear", "rayleigh": {"density": {"layers": [)" + layers + "]}}}";
    EXPECT_EQ(test::parameter_of([&] { Atmosphere::from_json_string(text); }), "rayleigh.density.layers");
    EXPECT_TRUE(contains(error_of([&] { Atmosphere::from_json_string(text); }), "between 1 and 32"));

    std::string cl;
    for (std::size_t i = 0; i <= SceneClouds::kMaxLayers; ++i) cl += std::string(i ? "," : "") + "{}";
    const std::string scene = R"({"version": 1, "clouds": {"layers": [)" + cl + "]}}";
    EXPECT_EQ(test::parameter_of([&] { SceneDescription::from_json_string(scene); }), "clouds.layers");
    EXPECT_TRUE(contains(error_of([&] { SceneDescription::from_json_string(scene); }), "at most 32"));
}

TEST_F(Hostile, VdbVoxelsFarFromTheOriginAreRefusedBeforeAllocating) {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto acc = grid->getAccessor();
    acc.setValue(openvdb::Coord(-(1 << 30), 0, 0), 1.0f);
    acc.setValue(openvdb::Coord(1 << 30, 0, 0), 1.0f);
    test::write_vdb(path("far.vdb"), {grid});
    const auto t0 = std::chrono::steady_clock::now();
    std::string what;
    try {
        VdbClouds clouds(path("far.vdb"), {});
    } catch (const InvalidArgument& e) {
        what = e.what();
        EXPECT_EQ(e.parameter(), "grid");
    }
    EXPECT_TRUE(contains(what, path("far.vdb"))) << what;
    EXPECT_TRUE(contains(what, "span at most")) << what;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}

TEST_F(Hostile, CorruptVdbIsAnErrorNamingTheFileNotACrash) {
    test::write_vdb(path("ok.vdb"),
                    {test::make_float_grid("density", 1.0, 8, [](int, int, int) { return 1.0f; })});
    std::string bytes = read("ok.vdb");
    ASSERT_GT(bytes.size(), 400u);
    // Flip bytes through the tree, one corruption at a time: every outcome is a clean error
    // or a valid grid, within bounded time.
    for (std::size_t at = 200; at < bytes.size(); at += bytes.size() / 17) {
        std::string bad = bytes;
        for (std::size_t k = at; k < std::min(bad.size(), at + 8); ++k) bad[k] = char(0xff);
        write("bad.vdb", bad);
        VdbCloudOptions o;
        o.max_memory_bytes = 64 << 20;
        try {
            VdbClouds clouds(path("bad.vdb"), o);
        } catch (const IoError& e) {
            EXPECT_TRUE(contains(e.what(), "bad.vdb")) << e.what();
        } catch (const InvalidArgument& e) {
            EXPECT_TRUE(contains(e.what(), "bad.vdb")) << e.what();
        } catch (const OutOfMemory& e) {
            EXPECT_TRUE(contains(e.what(), "bad.vdb")) << e.what();
        }
    }
}

// --- item 6: JSON errors name the file, the key path and the failure --------------------

TEST_F(Hostile, NumberOverflowNamesTheFileTheKeyPathAndTheRange) {
    write("atm.json", R"({"preset": "clear", "rayleigh": {"density": {"layers": [{"width_m": 1e999}]}}})");
    try {
        Atmosphere::from_json_file(path("atm.json"));
        FAIL() << "accepted 1e999";
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "rayleigh.density.layers[0].width_m");
        EXPECT_TRUE(contains(e.what(), "number out of range")) << e.what();
        EXPECT_TRUE(contains(e.what(), path("atm.json"))) << e.what();
    }
    write("scene.json", R"({"version": 1, "sun": {"direction": [0, 0, -1e400]}})");
    try {
        SceneDescription::from_json_file(path("scene.json"));
        FAIL() << "accepted -1e400";
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "sun.direction[2]");
        EXPECT_TRUE(contains(e.what(), "number out of range")) << e.what();
        EXPECT_TRUE(contains(e.what(), path("scene.json"))) << e.what();
    }
}

TEST_F(Hostile, MalformedAndTooDeepJsonIsAnInvalidArgument) {
    EXPECT_EQ(test::parameter_of([] { Atmosphere::from_json_string(R"({"mie": {"g": })"); }), "mie.g");
    EXPECT_TRUE(contains(error_of([] { Atmosphere::from_json_string("{\"a\": tru}"); }), "malformed JSON"));
    const std::string deep =
        R"({"version": 1, "comment": )" + std::string(100000, '[') + std::string(100000, ']') + "}";
    EXPECT_TRUE(
        contains(error_of([&] { SceneDescription::from_json_string(deep); }), "nested deeper than 64"));
    // The two schemas share one implementation: the same failure, the same error type.
    EXPECT_THROW(Atmosphere::from_json_file(path("missing.json")), IoError);
    EXPECT_THROW(SceneDescription::from_json_file(path("missing.json")), IoError);
}

// --- item 7: unique temporaries; cancellation and failures leave nothing ----------------

TEST_F(Hostile, ConcurrentJsonWritersToOnePathAllSucceedAndLeaveNoTemporary) {
    const Atmosphere atm = Atmosphere::preset("clear");
    std::vector<std::thread> threads;
    std::atomic<int> failures{0};
    for (int t = 0; t < 8; ++t)
        threads.emplace_back([&] {
            for (int k = 0; k < 10; ++k) {
                try {
                    atm.to_json_file(path("atm.json"), true);
                } catch (const std::exception&) {
                    ++failures;
                }
            }
        });
    for (auto& t : threads) t.join();
    EXPECT_EQ(failures.load(), 0);
    EXPECT_EQ(entries(), std::vector<std::string>{"atm.json"});
    EXPECT_EQ(Atmosphere::from_json_file(path("atm.json")).name, atm.name);
    // The written file gets a normal mode (not mkstemp's 0600).
    struct stat st {};
    ASSERT_EQ(::stat(path("atm.json").c_str(), &st), 0);
    const mode_t mask = ::umask(022);
    ::umask(mask);
    EXPECT_EQ(st.st_mode & 0777, 0666u & ~mask);
}

TEST_F(Hostile, CancelledExrWriteRemovesItsTemporary) {
    int asked = 0;
    ExrWriteOptions o;
    o.cancelled = [&] { return ++asked > 2; };  // cancel during the row bands
    EXPECT_THROW(write_exr(path("sky.exr"), small_image(), o), Cancelled);
    EXPECT_GT(asked, 2);
    EXPECT_TRUE(entries().empty());
}

TEST_F(Hostile, SignalCleanupRemovesLiveTemporaries) {
    const fs::path target = resolve_output_path(path("out.exr"), false);
    TemporaryFile tmp(target, path("out.exr"));
    ASSERT_TRUE(fs::exists(tmp.path()));
    EXPECT_TRUE(contains(tmp.path().filename().string(), ".out.exr.welkin-"));
    remove_temporaries_signal_safe();
    EXPECT_FALSE(fs::exists(tmp.path()));
    EXPECT_TRUE(entries().empty());
}

TEST_F(Hostile, FailedWriteReportsTheReasonAndRemovesTheTemporary) {
    // A file that appears while the write runs (no overwrite): refused, temporary removed.
    const fs::path target = resolve_output_path(path("x.json"), false);
    TemporaryFile tmp(target, path("x.json"));
    write("x.json", "theirs");
    tmp.write_all("mine", 4);
    EXPECT_TRUE(contains(error_of([&] { tmp.commit(false); }), "exists"));
    EXPECT_EQ(entries(), std::vector<std::string>{"x.json"});
    EXPECT_EQ(read("x.json"), "theirs");
    // A folder that does not exist: the reason is given.
    EXPECT_TRUE(
        contains(error_of([&] { write_file_atomic(path("no/such/x.json"), "x", false); }), "does not exist"));
}

// A VDB whose tree declares a blosc chunk of 2^56 bytes (found by tests/fuzz/fuzz_vdb.cpp):
// OpenVDB's allocation fails; the error is an OutOfMemory naming the file, not a bare
// std::bad_alloc, and it comes at once.
TEST_F(Hostile, VdbWhoseTreeDeclaresAHugeBufferIsOutOfMemoryNamingTheFile) {
    const std::string file = std::string(WELKIN_TEST_DATA_DIR) + "/../fuzz/corpus/vdb/blosc_huge_chunk.vdb";
    ASSERT_TRUE(fs::exists(file));
    try {
        VdbClouds clouds(file, {});
        FAIL() << "accepted a corrupt VDB";
    } catch (const OutOfMemory& e) {
        EXPECT_TRUE(contains(e.what(), "blosc_huge_chunk.vdb")) << e.what();
    } catch (const IoError& e) {
        EXPECT_TRUE(contains(e.what(), "blosc_huge_chunk.vdb"))
            << e.what();  // a tighter check may come first
    }
}

// A VDB whose tree makes OpenVDB 10 write past a node's buffer (io::bloscFromStream, found
// by tests/fuzz/fuzz_vdb.cpp): the tree is read first in a child process, which dies; the
// host refuses the file with an error naming it and keeps running.
TEST_F(Hostile, VdbThatOverwritesOpenVdbsHeapIsRefusedAndTheHostLives) {
    const std::string file =
        std::string(WELKIN_TEST_DATA_DIR) + "/../fuzz/corpus/vdb/blosc_heap_buffer_overflow.vdb";
    ASSERT_TRUE(fs::exists(file));
    for (int attempt = 0; attempt < 3; ++attempt) {  // the host's heap stays sound: again and again
        const std::string message = error_of([&] { VdbClouds clouds(file, {}); });
        EXPECT_TRUE(contains(message, file)) << message;
        EXPECT_TRUE(contains(message, "corrupt data")) << message;
        EXPECT_TRUE(contains(message, "reader process")) << message;
    }
}

// Every input of the VDB fuzz corpus (the seeds and the fuzzer's findings: a 2^56-byte
// blosc chunk, root node counts of 2.6e9, a fixed-size metadata value whose byte count
// lies) ends at once in a valid grid or a welkin error naming the file, in little memory.
TEST_F(Hostile, EveryVdbOfTheFuzzCorpusEndsAtOnceInAGridOrAnErrorNamingTheFile) {
    const fs::path corpus = fs::path(WELKIN_TEST_DATA_DIR) / ".." / "fuzz" / "corpus" / "vdb";
    std::size_t n = 0;
    for (const auto& entry : fs::directory_iterator(corpus)) {
        ++n;
        const std::string file = entry.path().string();
        VdbCloudOptions o;
        o.max_memory_bytes = 64 << 20;
        const auto t0 = std::chrono::steady_clock::now();
        try {
            VdbClouds clouds(file, o);
        } catch (const IoError& e) {
            EXPECT_TRUE(contains(e.what(), file)) << e.what();
        } catch (const InvalidArgument& e) {
            EXPECT_TRUE(contains(e.what(), file)) << e.what();
        } catch (const OutOfMemory& e) {
            EXPECT_TRUE(contains(e.what(), file)) << e.what();
        }
        EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0) << file;
    }
    EXPECT_GE(n, 5u);
}
