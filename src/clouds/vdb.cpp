// SPDX-License-Identifier: Apache-2.0
// Clouds from an OpenVDB file; see clouds/vdb.hpp.
#include "welkin/clouds/vdb.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <vector>

#include <fcntl.h>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <oneapi/tbb/global_control.h>
#include <openvdb/Exceptions.h>
#include <openvdb/io/DelayedLoadMetadata.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Count.h>
#include <openvdb/tools/Interpolation.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "welkin/base/error.hpp"

namespace welkin {

struct VdbClouds::Impl {
    std::string path, grid_name;
    openvdb::FloatGrid::Ptr grid;
    glm::dmat4 index_to_world{1.0}, world_to_index{1.0};
    double density_scale = 1.0;
    std::uint64_t negatives = 0, memory = 0;
    float max_value = 0.0f;
    double voxel_size_m = 1.0;
    // The majorant grid: cells of `cell` voxels from index `origin`, n[0] x n[1] x n[2].
    openvdb::Coord origin;
    int cell = 8;
    int n[3] = {0, 0, 0};
    std::vector<float> majorant;  // grid values (not yet scaled)
    float& cell_at(int i, int j, int k) { return majorant[(std::size_t(k) * n[1] + j) * n[0] + i]; }
    float cell_at(int i, int j, int k) const { return majorant[(std::size_t(k) * n[1] + j) * n[0] + i]; }

    std::string where() const { return fmt::format("grid '{}' of VDB file '{}'", grid_name, path); }

    // The steps of VdbClouds::load once the grid is read and its header checked.
    void check_values(VdbCloudOptions::Negative negative);
    void set_transforms(const VdbCloudOptions& options);
    void build_majorant();
};

namespace {

// OpenVDB with one metadata type taken out. io::DelayedLoadMetadata (type "__delayedload",
// what every OpenVDB since 6 writes with each grid for delayed loading, which Welkin never
// uses) blosc-decompresses tables from the file as soon as a grid's metadata is read, and
// libblosc reads out of bounds on a corrupt chunk (a SEGV in the fuzzer's own process:
// tests/fuzz/corpus/vdb/delayed_load_blosc_segv.vdb). Unregistered, OpenVDB reads the
// entry as UnknownMetadata, its declared bytes as they are, and drops it (MetaMap::readMeta
// keeps no unknown type whose name starts with "__"). Process-wide: the wheel carries its
// own OpenVDB, and nothing else in Welkin reads delayed-load tables.
void initialize_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] {
        openvdb::initialize();
        openvdb::Metadata::unregisterType(openvdb::io::DelayedLoadMetadata::staticTypeName());
    });
}

std::uint64_t metadata_u64(const openvdb::GridBase& meta, const char* name) {
    if (const auto v = meta.getMetadata<openvdb::Int64Metadata>(name))
        return std::uint64_t(std::max<openvdb::Int64>(0, v->value()));
    return 0;
}

// OpenVDB allocates what a length field in the file declares before it reads the bytes (a
// string of 2^32 - 1 bytes, 2^32 metadata entries): a few flipped bytes cost gigabytes and
// seconds before its error. This walks the file's own structure first, as OpenVDB's
// reader will (io/Archive.cc: header; File::open: the file's metadata and the grid
// descriptors; Archive::readGrid: each grid's compression flags and metadata), and checks
// that every count and length fits in what is left of the file. IoError naming the file.
class VdbStructureCheck {
public:
    VdbStructureCheck(const std::string& path, const std::string& grid)
        : path_(path), grid_(grid), in_(path, std::ios::binary) {
        in_.seekg(0, std::ios::end);
        size_ = std::uint64_t(std::max<std::streamoff>(0, in_.tellg()));
        in_.seekg(0);
    }

    void run() {
        if (u32() != std::uint32_t(openvdb::OPENVDB_MAGIC) || u32() != 0)
            fail("it does not start with the OpenVDB magic number");
        const std::uint32_t version = u32();
        // OpenVDB only warns about a version newer than its own, then misreads the rest.
        if (version > std::uint32_t(openvdb::OPENVDB_FILE_VERSION))
            fail(fmt::format("file format version {} is newer than this OpenVDB's ({})", version,
                             openvdb::OPENVDB_FILE_VERSION));
        // Older layouts (OpenVDB's NODE_MASK_COMPRESSION is 222; OpenVDB 10 writes 224) are not
        // walked here, and OpenVDB's File::open would read their metadata (strings of any
        // declared length) in this process: refused.
        if (version < 222)
            fail(
                fmt::format("file format version {} is older than 222, the oldest layout Welkin reads; "
                            "re-save the file with a current OpenVDB",
                            version));
        skip(8);  // library version
        const bool offsets = bytes(1)[0] != 0;
        skip(36);  // uuid
        meta_map();
        // Without grid offsets OpenVDB reads every grid's tree while opening the file, before
        // any check of ours; every OpenVDB since file version 212 writes them.
        if (!offsets) fail("it has no grid offsets (written by an OpenVDB older than 2.0?)");
        const std::uint32_t grids = u32();
        need(std::uint64_t(grids) * 32, "grid count");
        struct Grid {
            std::uint64_t pos, block;
            bool float_tree, instance;
        };
        std::vector<Grid> positions;
        for (std::uint32_t g = 0; g < grids; ++g) {
            string();                                 // unique name
            const std::string type = string();        // tree type
            const bool instance = !string().empty();  // instance parent (version >= 216)
            const std::uint64_t grid_pos = u64(), block_pos = u64(), end_pos = u64();
            if (!(grid_pos <= block_pos && block_pos <= end_pos && end_pos <= size_))
                fail(fmt::format("grid {} has offsets [{}, {}, {}] outside the file ({} bytes)", g, grid_pos,
                                 block_pos, end_pos, size_));
            positions.push_back({grid_pos, block_pos, type == "Tree_float_5_4_3", instance});
            seek(end_pos);
        }
        for (const Grid& g : positions) {
            seek(g.pos);
            skip(4);  // compression flags (version >= 222)
            meta_map();
            if (!g.float_tree || g.instance) continue;
            // Grid::readTransform: the map's type name, then its fixed-size data.
            const std::string map = string();
            static const std::pair<const char*, int> kMapBytes[] = {{"AffineMap", 128},
                                                                    {"UnitaryMap", 128},
                                                                    {"ScaleMap", 120},
                                                                    {"UniformScaleMap", 120},
                                                                    {"TranslationMap", 24},
                                                                    {"ScaleTranslateMap", 144},
                                                                    {"UniformScaleTranslateMap", 144}};
            int bytes = -1;
            for (const auto& [name, n] : kMapBytes)
                if (map == name) bytes = n;
            if (bytes < 0) return;  // a frustum (refused later) or an unknown map (OpenVDB's error)
            skip(std::uint64_t(bytes));
            // Tree::readTopology: a buffer count; RootNode::readTopology: the background,
            // then the numbers of tiles (17 bytes each) and of children (12 bytes of origin and
            // at least two 4096-byte node masks each), all before the tree's buffers.
            skip(4);
            skip(4);
            const std::uint64_t tiles = u32(), children = u32();
            const std::uint64_t room = g.block > pos_ ? g.block - pos_ : 0;
            if (tiles * 17 + children * (12 + 2 * 4096) > room)
                fail(fmt::format(
                    "the grid's root node declares {} tiles and {} child nodes, more than its {} bytes "
                    "of topology can hold",
                    tiles, children, room));
        }
    }

private:
    [[noreturn]] void fail(const std::string& why) const {
        throw IoError(fmt::format("VDB file '{}' (grid '{}'): corrupt: {}", path_, grid_, why));
    }
    void need(std::uint64_t n, const char* what) const {
        if (n > size_ - pos_)
            fail(fmt::format("{} at byte {} declares {} bytes, but only {} remain in the file", what, pos_, n,
                             size_ - pos_));
    }
    std::string bytes(std::uint64_t n) {
        need(n, "a field");
        std::string b(n, '\0');
        in_.read(b.data(), std::streamsize(n));
        if (!in_) fail(fmt::format("cannot read {} bytes at byte {}", n, pos_));
        pos_ += n;
        return b;
    }
    void skip(std::uint64_t n) {
        need(n, "a field");
        seek(pos_ + n);
    }
    void seek(std::uint64_t p) {
        if (p > size_)
            fail(fmt::format("an offset ({}) lies beyond the end of the file ({} bytes)", p, size_));
        in_.seekg(std::streamoff(p));
        pos_ = p;
    }
    std::uint32_t u32() {
        std::uint32_t v;
        std::memcpy(&v, bytes(4).data(), 4);
        return v;
    }
    std::uint64_t u64() {
        std::uint64_t v;
        std::memcpy(&v, bytes(8).data(), 8);
        return v;
    }
    std::string string() {
        const std::uint32_t n = u32();
        need(n, "a string");
        if (n > 256) {
            skip(n);
            return std::string(256, '?');
        }
        return bytes(n);
    }
    // MetaMap::readMeta: a count, then (name, type name, byte count + value) per entry.
    void meta_map() {
        const std::uint32_t count = u32();
        need(std::uint64_t(count) * 12, "a metadata count");
        // TypedMetadata<T>::readValue reads sizeof(T) bytes whatever the byte count says:
        // follow it, or the walk would part from OpenVDB's own.
        static const std::pair<const char*, int> kFixed[] = {
            {"bool", 1},   {"float", 4},  {"double", 8}, {"int32", 4},  {"int64", 8},  {"vec2i", 8},
            {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
            {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
        for (std::uint32_t i = 0; i < count; ++i) {
            string();
            const std::string type = string();
            const std::uint32_t n = u32();
            // An unregistered type (the delayed-load table among them: initialize_openvdb)
            // is read as its n bytes.
            std::uint64_t size = n;
            for (const auto& [name, bytes] : kFixed)
                if (type == name) size = std::uint64_t(bytes);
            need(size, "a metadata value");
            skip(size);
        }
    }

    std::string path_, grid_;
    std::ifstream in_;
    std::uint64_t size_ = 0, pos_ = 0;
};

// The grid's tree is parsed only in a child process; the host parses what the child wrote.
// OpenVDB 10 trusts the lengths inside a grid's tree: io::bloscFromStream (and
// io::unzipFromStream) copy an uncompressed chunk of the length the file declares into the
// node's buffer and only then compare that length with the buffer's size (io/Compression.cc),
// so a corrupt or hostile tree overwrites the heap of the process that parses it before
// OpenVDB throws (tests/fuzz/corpus/vdb/blosc_heap_buffer_overflow.vdb,
// tests/fuzz/corpus/vdb/crash_ball_*.vdb). Everything up to the tree is bounded by VdbStructureCheck;
// the tree itself cannot be checked without parsing it. So the child parses the file's tree
// and writes the grid back through a pipe (GridPipe below), and the host builds the grid
// from that, never reading the file's tree. A child that throws (the exception may follow
// an overwrite of its heap), dies or outlives kChildSeconds only refuses the file; the
// host's heap is never touched by it. The price: the grid is copied once more, and the
// host holds that copy while it builds the grid.
//
// TBB and fork: fork copies the calling thread alone, and TBB's scheduler, whose worker
// threads stay behind in the host, may hold its locks at that moment; under the fuzzer
// children hung for good on a futex in libtbb, in OpenVDB's writer (LeafManager in
// Archive::writeGrid) and in a tree's destructor (Tree::clear). So the host ends TBB's
// workers before it forks (run_tree_reader), and the child's own work is serial where it
// can be: OpenVDB's reader, a serial memory count, and GridPipe's writer.
constexpr unsigned kChildSeconds = 600;

void write_all_fd(int fd, const char* data, std::size_t size) {
    while (size > 0) {
        const ssize_t n = ::write(fd, data, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) ::_exit(3);
        data += n;
        size -= std::size_t(n);
    }
}

// The grid through the pipe, written by the child with serial loops over the tree and read
// by the host, which checks every count against what arrived (the child's heap may have
// been overwritten before it wrote). Native byte order (the same binary at both ends):
//   u8 map: 0 affine, 1 not affine (a frustum), 2 singular; then, if affine, 16 f64, the
//     index-to-world matrix as OpenVDB's Mat4d (row vectors);
//   f32 background;
//   u64 tile count, then per tile: u8 level (1-3), u8 active, 3 i32 origin, f32 value
//     (the tiles that differ from an inactive background);
//   u64 leaf count, then per leaf: 3 i32 origin, 8 u64 of the value mask, 512 f32 values.
class GridPipe {
public:
    using Leaf = openvdb::FloatTree::LeafNodeType;

    static std::string write(const openvdb::FloatGrid& g) {
        std::string out;
        std::uint8_t map = 0;
        openvdb::Mat4d m;
        if (!g.transform().isLinear()) {
            map = 1;
        } else {
            try {
                m = g.transform().baseMap()->getAffineMap()->getMat4();
            } catch (const openvdb::ArithmeticError&) {
                map = 2;
            }
        }
        put(out, map);
        if (map == 0)
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) put(out, double(m(r, c)));
        const float background = g.background();
        put(out, background);
        const std::size_t tiles_at = out.size();
        std::uint64_t tiles = 0, leaves = 0;
        put(out, tiles);
        for (auto it = g.tree().cbeginValueAll(); it; ++it) {
            if (it.isVoxelValue() || (!it.isValueOn() && *it == background)) continue;
            put(out, std::uint8_t(it.getLevel()));
            put(out, std::uint8_t(it.isValueOn()));
            put_coord(out, it.getCoord());
            put(out, float(*it));
            ++tiles;
        }
        std::memcpy(out.data() + tiles_at, &tiles, sizeof tiles);
        const std::size_t leaves_at = out.size();
        put(out, leaves);
        for (auto it = g.tree().cbeginLeaf(); it; ++it) {
            put_coord(out, it->origin());
            for (openvdb::Index w = 0; w < Leaf::NodeMaskType::WORD_COUNT; ++w)
                put(out, it->getValueMask().template getWord<std::uint64_t>(w));
            out.append(reinterpret_cast<const char*>(it->buffer().data()), Leaf::SIZE * sizeof(float));
            ++leaves;
        }
        std::memcpy(out.data() + leaves_at, &leaves, sizeof leaves);
        return out;
    }

    // The grid, or an exception naming `where`.
    static openvdb::FloatGrid::Ptr read(const std::string& data, const std::string& where) {
        GridPipe in(data, where);
        const auto degenerate = [&](const std::string& why) {
            return InvalidArgument(
                "grid", fmt::format("{} has a degenerate transform (its voxels have no volume{}); refused",
                                    where, why));
        };
        const auto map = in.get<std::uint8_t>();
        if (map == 1)
            throw InvalidArgument(
                "grid",
                fmt::format("{} has a non-affine (frustum) transform, which Welkin does not read", where));
        if (map == 2) throw degenerate("");
        if (map != 0) in.fail("an unknown transform");
        openvdb::Mat4d m;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m(r, c) = in.get<double>();
        const openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(in.get<float>());
        try {
            g->setTransform(openvdb::math::Transform::createLinearTransform(m));
        } catch (const openvdb::Exception& e) {
            throw degenerate(std::string(": ") + e.what());
        }
        const std::uint64_t tiles = in.count(1 + 1 + 12 + 4);
        for (std::uint64_t i = 0; i < tiles; ++i) {
            const auto level = in.get<std::uint8_t>();
            const bool active = in.get<std::uint8_t>() != 0;
            const openvdb::Coord origin = in.coord();
            const float value = in.get<float>();
            if (level < 1 || level > 3) in.fail("a tile's level");
            g->tree().addTile(level, origin, value, active);
        }
        const std::uint64_t leaves =
            in.count(12 + 8 * Leaf::NodeMaskType::WORD_COUNT + Leaf::SIZE * sizeof(float));
        for (std::uint64_t i = 0; i < leaves; ++i) {
            auto leaf = std::make_unique<Leaf>(in.coord(), g->background());
            for (openvdb::Index w = 0; w < Leaf::NodeMaskType::WORD_COUNT; ++w)
                leaf->getValueMask().template getWord<std::uint64_t>(w) = in.get<std::uint64_t>();
            in.bytes(reinterpret_cast<char*>(leaf->buffer().data()), Leaf::SIZE * sizeof(float));
            g->tree().addLeaf(leaf.release());
        }
        if (in.pos_ != data.size()) in.fail("bytes after the grid");
        return g;
    }

private:
    GridPipe(const std::string& data, const std::string& where) : data_(data), where_(where) {}

    template <typename T>
    static void put(std::string& out, T v) {
        out.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    static void put_coord(std::string& out, const openvdb::Coord& c) {
        for (int a = 0; a < 3; ++a) put(out, std::int32_t(c[a]));
    }
    [[noreturn]] void fail(const char* what) const {
        throw IoError(fmt::format("{}: the reader process returned a malformed grid ({} at byte {}); refused",
                                  where_, what, pos_));
    }
    void bytes(char* to, std::size_t n) {
        if (n > data_.size() - pos_) fail("a short record");
        std::memcpy(to, data_.data() + pos_, n);
        pos_ += n;
    }
    template <typename T>
    T get() {
        T v;
        bytes(reinterpret_cast<char*>(&v), sizeof v);
        return v;
    }
    openvdb::Coord coord() {
        openvdb::Coord c;
        for (int a = 0; a < 3; ++a) c[a] = get<std::int32_t>();
        return c;
    }
    // A count of records of `size` bytes that the rest of the data can hold.
    std::uint64_t count(std::uint64_t size) {
        const auto n = get<std::uint64_t>();
        if (n > (data_.size() - pos_) / size) fail("a count beyond the data");
        return n;
    }

    const std::string& data_;
    const std::string& where_;
    std::size_t pos_ = 0;
};

// The child: one tag byte, then the grid through GridPipe ('G'), an exception's message
// ('E'), nothing (out of memory, 'M') or the grid's memory use in bytes (over the limit, 'L').
[[noreturn]] void tree_reader_child(int fd, const std::string& path, const std::string& grid,
                                    std::uint64_t max_bytes) {
    // Only async-signal-safe calls are certain after fork in a threaded host; OpenVDB's
    // reader and GridPipe's writer are serial and the allocator is fork-aware, which is what
    // this relies on (TBB: see above).
    for (int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGILL, SIGFPE, SIGALRM, SIGPIPE}) ::signal(sig, SIG_DFL);
    ::alarm(kChildSeconds);
    char tag = 'G';
    std::string message;
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        const openvdb::GridBase::Ptr g = file.readGrid(grid);
        file.close();
        // Never destroyed: the child ends with _exit, and a tree's destructor runs a
        // parallel loop (Tree::clear), which needs TBB (see above).
        new openvdb::GridBase::Ptr(g);
        const openvdb::FloatGrid::Ptr fg = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
        if (!fg) throw openvdb::TypeError("the grid is not a FloatGrid");
        const openvdb::Index64 memory = openvdb::tools::memUsage(fg->tree(), /*threaded=*/false);
        if (memory > max_bytes) {
            tag = 'L';
            message = std::to_string(memory);
        } else {
            message = GridPipe::write(*fg);
        }
    } catch (const std::bad_alloc&) {
        tag = 'M';
        message.clear();
    } catch (const std::exception& e) {
        tag = 'E';
        message = e.what();
    } catch (...) {
        tag = 'E';
        message = "unknown exception";
    }
    write_all_fd(fd, &tag, 1);
    write_all_fd(fd, message.data(), message.size());
    ::_exit(0);
}

// Everything the child writes, up to `cap` bytes (false beyond it).
bool read_pipe(int fd, std::string& data, std::uint64_t cap) {
    char buffer[1 << 16];
    while (true) {
        const ssize_t n = ::read(fd, buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return true;
        if (data.size() + std::size_t(n) > cap) return false;
        data.append(buffer, std::size_t(n));
    }
}

// The child's result: the grid's GridPipe records (tag stripped) or an exception naming the file.
std::string run_tree_reader(const std::string& path, const std::string& grid, const std::string& where,
                            std::uint64_t max_bytes) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
        throw IoError(fmt::format("{}: cannot start the reader process: {}", where, std::strerror(errno)));
    // TBB's worker threads end here (the next parallel loop starts them again), so that no
    // worker holds one of TBB's locks in the copy the child gets; the child's own parallel
    // loops (OpenVDB destroys a tree with one) then start a scheduler of their own. When
    // another thread is running TBB work at this moment, finalize declines and the fork
    // goes ahead with the workers running: a child hung on their locks is then stopped by
    // kChildSeconds.
    {
        oneapi::tbb::task_scheduler_handle handle{oneapi::tbb::attach{}};
        (void)oneapi::tbb::finalize(handle, std::nothrow);
    }
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::close(fds[0]);
        tree_reader_child(fds[1], path, grid, max_bytes);
    }
    ::close(fds[1]);
    if (pid < 0) {
        ::close(fds[0]);
        throw IoError(fmt::format("{}: cannot start the reader process: {}", where, std::strerror(errno)));
    }
    std::string data;
    // A grid within the limit: its leaves' values and masks, its tiles (GridPipe).
    const bool complete = read_pipe(fds[0], data, 2 * max_bytes + (std::uint64_t(1) << 24));
    if (!complete) ::kill(pid, SIGKILL);
    ::close(fds[0]);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR)
            throw IoError(fmt::format("{}: lost the reader process: {}", where, std::strerror(errno)));
    }
    if (!complete)
        throw InvalidArgument("max_memory_bytes", fmt::format("{} takes more than the limit of {:.1f} MiB",
                                                              where, max_bytes / 1048576.0));
    if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM)
        throw IoError(
            fmt::format("{}: reading its tree took longer than {} s; refused", where, kChildSeconds));
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || data.empty())
        throw IoError(
            fmt::format("{}: corrupt data: reading its tree ended the reader process ({}); refused", where,
                        WIFSIGNALED(status) ? ::strsignal(WTERMSIG(status))
                                            : fmt::format("exit code {}", WEXITSTATUS(status)).c_str()));
    const char tag = data[0];
    data.erase(0, 1);
    if (tag == 'E')
        throw IoError(fmt::format(
            "{}: corrupt data: the reader process could not read its tree ({}); refused", where, data));
    if (tag == 'M')
        throw OutOfMemory(
            fmt::format("{}: out of memory while reading its tree (a corrupt or very large "
                        "grid?); the limit is max_memory_bytes",
                        where));
    if (tag == 'L')
        throw InvalidArgument("max_memory_bytes",
                              fmt::format("{} takes {:.1f} MiB, more than the limit of {:.1f} MiB", where,
                                          std::stod(data) / 1048576.0, max_bytes / 1048576.0));
    return data;
}

// The grid, parsed in a child (run_tree_reader) and built here from what it wrote.
openvdb::FloatGrid::Ptr read_grid_isolated(const std::string& path, const std::string& grid,
                                           const std::string& where, std::uint64_t max_bytes) {
    return GridPipe::read(run_tree_reader(path, grid, where, max_bytes), where);
}

// The active bounding box within the documented limits (docs/limits.md), or an
// InvalidArgument naming the grid.
void check_extent(const openvdb::Coord& lo, const openvdb::Coord& hi, const std::string& where) {
    for (int a = 0; a < 3; ++a) {
        const std::int64_t l = lo[a], h = hi[a];
        if (l < -kMaxVdbCoordinate || h > kMaxVdbCoordinate || l > h || h - l + 1 > kMaxVdbExtent)
            throw InvalidArgument(
                "grid", fmt::format("{} has active voxels from {} to {}: coordinates must lie in "
                                    "[-{}, {}] and span at most {} voxels along each axis",
                                    where, lo.asVec3i().str(), hi.asVec3i().str(), kMaxVdbCoordinate,
                                    kMaxVdbCoordinate, kMaxVdbExtent));
    }
}

}  // namespace

// Values: non-finite ones are rejected, negative ones clamped (and counted) or rejected.
void VdbClouds::Impl::check_values(VdbCloudOptions::Negative negative) {
    for (auto it = grid->beginValueOn(); it; ++it) {
        const float v = *it;
        if (!std::isfinite(v))
            throw InvalidArgument("grid", fmt::format("{} holds a non-finite value at {}", where(),
                                                      it.getCoord().asVec3i().str()));
        if (v < 0.0f) {
            if (negative == VdbCloudOptions::Negative::Reject)
                throw InvalidArgument(
                    "grid", fmt::format("{} holds a negative density {} at {} (densities must be >= 0; "
                                        "the Clamp policy sets them to 0)",
                                        where(), v, it.getCoord().asVec3i().str()));
            negatives += it.isVoxelValue() ? 1 : it.getVoxelCount();
            it.setValue(0.0f);
        } else {
            max_value = std::max(max_value, v);
        }
    }
}

// Index -> world (file transform, voxel placement, matrix_world), refusing a singular one.
void VdbClouds::Impl::set_transforms(const VdbCloudOptions& options) {
    // Transforms: index -> object from the file (OpenVDB's Mat4d acts on row vectors,
    // p' = p M, so its transpose is glm's column-vector matrix), then object -> world.
    // GridPipe::read built the map from an invertible matrix (a frustum or a singular map
    // refused there), so OpenVDB's inversion here cannot throw.
    const openvdb::Mat4d vm = grid->transform().baseMap()->getAffineMap()->getMat4();
    glm::dmat4 index_to_object;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) index_to_object[c][r] = vm(c, r);
    // The voxel placement (see the header): Blender's puts voxel ijk's value at index point
    // ijk + 1/2, i.e. the grid's index frame is translated by +1/2 before its transform.
    const double offset = options.placement == VdbCloudOptions::VoxelPlacement::Blender ? 0.5 : 0.0;
    const glm::dmat4 placement = glm::translate(glm::dmat4(1.0), glm::dvec3(offset));
    index_to_world = options.matrix_world * index_to_object * placement;
    const double det = glm::determinant(glm::dmat3(index_to_world));
    if (!(std::abs(det) > 1e-30) || !std::isfinite(det))
        throw InvalidArgument("matrix_world",
                              fmt::format("maps {} to a degenerate (singular) volume", where()));
    world_to_index = glm::inverse(index_to_world);
    voxel_size_m = std::cbrt(std::abs(det));
}

// The majorant grid over the active bounding box, dilated by one cell.
void VdbClouds::Impl::build_majorant() {
    // The majorant grid over the active bounding box, one voxel of margin for interpolation.
    openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    box.expand(1);
    const openvdb::Coord extent = box.dim();
    const int largest = std::max({extent.x(), extent.y(), extent.z()});
    cell = std::max(8, (largest + 63) / 64);
    origin = box.min();
    for (int a = 0; a < 3; ++a) n[a] = (extent[a] + cell - 1) / cell;
    majorant.assign(std::size_t(n[0]) * n[1] * n[2], 0.0f);
    const auto cell_of = [&](int a, int i) { return std::clamp((i - origin[a]) / cell, 0, n[a] - 1); };
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        const float v = *it;
        if (!(v > 0.0f)) continue;
        openvdb::CoordBBox b;
        it.getBoundingBox(b);
        for (int k = cell_of(2, b.min().z()); k <= cell_of(2, b.max().z()); ++k)
            for (int j = cell_of(1, b.min().y()); j <= cell_of(1, b.max().y()); ++j)
                for (int i = cell_of(0, b.min().x()); i <= cell_of(0, b.max().x()); ++i)
                    cell_at(i, j, k) = std::max(cell_at(i, j, k), v);
    }
    // Dilate by one cell: a voxel next to a cell's face reaches into it by interpolation.
    std::vector<float> own = majorant;
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                float v = 0.0f;
                for (int dk = -1; dk <= 1; ++dk)
                    for (int dj = -1; dj <= 1; ++dj)
                        for (int di = -1; di <= 1; ++di) {
                            const int ii = i + di, jj = j + dj, kk = k + dk;
                            if (ii < 0 || jj < 0 || kk < 0 || ii >= n[0] || jj >= n[1] || kk >= n[2])
                                continue;
                            v = std::max(v, own[(std::size_t(kk) * n[1] + jj) * n[0] + ii]);
                        }
                cell_at(i, j, k) = v;
            }
}

VdbClouds::VdbClouds(const std::string& path, const VdbCloudOptions& options)
    : impl_(std::make_unique<Impl>()) {
    try {
        load(path, options);
    } catch (const std::bad_alloc& e) {
        if (dynamic_cast<const OutOfMemory*>(&e)) throw;
        throw OutOfMemory(
            fmt::format("VDB file '{}' (grid '{}'): out of memory while reading it (a corrupt or "
                        "very large grid?); the limit is max_memory_bytes",
                        path, options.grid));
    } catch (const openvdb::Exception& e) {
        // Whatever OpenVDB refuses in a grid that the checks above let through.
        throw IoError(
            fmt::format("VDB file '{}' (grid '{}'): refused by OpenVDB: {}", path, options.grid, e.what()));
    }
}

void VdbClouds::load(const std::string& path, const VdbCloudOptions& options) {
    Impl& m = *impl_;
    m.path = path;
    m.grid_name = options.grid;
    require_in_range("density_scale", options.density_scale, 0.0, 1e6, "m^-1");
    if (options.max_memory_bytes < 1) throw InvalidArgument("max_memory_bytes", "must be at least 1");
    if (options.grid.empty())
        throw InvalidArgument("grid",
                              fmt::format("must name a grid of VDB file '{}', got an empty name", path));
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            require_finite(fmt::format("matrix_world[{}][{}]", r, c), options.matrix_world[c][r]);
    m.density_scale = options.density_scale;
    initialize_openvdb();

    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(fmt::format("VDB file '{}' (grid '{}'): no such file", path, options.grid));

    VdbStructureCheck(path, options.grid).run();

    openvdb::io::File file(path);
    openvdb::GridBase::Ptr meta;
    std::vector<std::string> names;
    try {
        file.open(/*delayLoad=*/false);
        for (auto it = file.beginName(); it != file.endName(); ++it) names.push_back(it.gridName());
        if (!file.hasGrid(options.grid)) {
            std::string list;
            for (const auto& s : names) list += (list.empty() ? "'" : ", '") + s + "'";
            throw InvalidArgument("grid", fmt::format("VDB file '{}' has no grid '{}' (its grids: {})", path,
                                                      options.grid, list.empty() ? "none" : list));
        }
        meta = file.readGridMetadata(options.grid);
    } catch (const InvalidArgument&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(fmt::format("VDB file '{}' (grid '{}'): cannot be read as OpenVDB: {}", path,
                                  options.grid, e.what()));
    }
    if (!meta->isType<openvdb::FloatGrid>())
        throw InvalidArgument(
            "grid", fmt::format("{} is of type '{}'; Welkin reads float grids (FloatGrid) only", m.where(),
                                meta->type()));
    // The memory estimate comes from the file's metadata, before any voxel is read.
    const std::uint64_t mem = metadata_u64(*meta, openvdb::GridBase::META_FILE_MEM_BYTES);
    const std::uint64_t voxels = metadata_u64(*meta, openvdb::GridBase::META_FILE_VOXEL_COUNT);
    const std::uint64_t estimate =
        std::max(mem, voxels > (std::uint64_t(1) << 60) ? ~std::uint64_t(0) : voxels * sizeof(float));
    // The extent, from the file's metadata (OpenVDB writes it with every grid), before the
    // tree is read: a corrupt or hostile bounding box stops here.
    const auto bmin = meta->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
    const auto bmax = meta->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
    if (bmin && bmax && voxels > 0)
        check_extent(openvdb::Coord(bmin->value()), openvdb::Coord(bmax->value()), m.where());
    if (estimate > options.max_memory_bytes)
        throw InvalidArgument(
            "max_memory_bytes",
            fmt::format("{} needs about {:.1f} MiB ({} active voxels), more than the limit of {:.1f} MiB",
                        m.where(), estimate / 1048576.0, voxels, options.max_memory_bytes / 1048576.0));
    file.close();
    m.grid = read_grid_isolated(path, options.grid, m.where(), options.max_memory_bytes);
    if (!m.grid) throw InvalidArgument("grid", fmt::format("{} is not a FloatGrid", m.where()));
    m.memory = m.grid->memUsage();
    if (m.memory > options.max_memory_bytes)
        throw InvalidArgument("max_memory_bytes",
                              fmt::format("{} takes {:.1f} MiB, more than the limit of {:.1f} MiB", m.where(),
                                          m.memory / 1048576.0, options.max_memory_bytes / 1048576.0));
    if (m.grid->activeVoxelCount() == 0)
        throw InvalidArgument("grid", fmt::format("{} is empty (no active voxels)", m.where()));
    {
        const openvdb::CoordBBox active = m.grid->evalActiveVoxelBoundingBox();
        check_extent(active.min(), active.max(), m.where());
    }
    const float background = m.grid->background();
    if (background != 0.0f)
        throw InvalidArgument("grid",
                              fmt::format("{} has background value {}; a density grid must have background 0 "
                                          "(a fog volume), or it would fill all of space",
                                          m.where(), background));

    m.check_values(options.negative);
    m.set_transforms(options);
    m.build_majorant();
}

VdbClouds::~VdbClouds() = default;

double VdbClouds::sigma_t(const glm::dvec3& p) const {
    const Impl& m = *impl_;
    const glm::dvec4 q = m.world_to_index * glm::dvec4(p, 1.0);
    const openvdb::FloatGrid::ConstUnsafeAccessor acc = m.grid->getConstUnsafeAccessor();
    const float v = openvdb::tools::BoxSampler::sample(acc, openvdb::Vec3d(q.x, q.y, q.z));
    return m.density_scale * std::max(0.0, double(v));
}

// The 3D DDA through the majorant cells, in index space (t is the world ray's parameter).
void VdbClouds::segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const {
    out.clear();
    const Impl& m = *impl_;
    if (!(m.density_scale > 0.0) || !(m.max_value > 0.0)) return;
    const glm::dvec3 o = glm::dvec3(m.world_to_index * glm::dvec4(ray.origin, 1.0));
    const glm::dvec3 d = glm::dvec3(m.world_to_index * glm::dvec4(ray.direction, 0.0));
    // Cell space: c = (index - origin) / cell, cells [0, n).
    const glm::dvec3 co = (o - glm::dvec3(m.origin.x(), m.origin.y(), m.origin.z())) / double(m.cell);
    const glm::dvec3 cd = d / double(m.cell);
    const CloudRay cray{co, cd};
    double t0 = 0.0, t1 = t_max;
    if (!clip_ray_to_box(cray, glm::dvec3(0.0), glm::dvec3(m.n[0], m.n[1], m.n[2]), t0, t1)) return;
    int cell[3], step[3];
    double next[3], delta[3];
    const glm::dvec3 p0 = co + t0 * cd;
    for (int a = 0; a < 3; ++a) {
        cell[a] = std::clamp(int(std::floor(p0[a])), 0, m.n[a] - 1);
        if (cd[a] > 0.0) {
            step[a] = 1;
            delta[a] = 1.0 / cd[a];
            next[a] = t0 + (cell[a] + 1 - p0[a]) * delta[a];
        } else if (cd[a] < 0.0) {
            step[a] = -1;
            delta[a] = -1.0 / cd[a];
            next[a] = t0 + (p0[a] - cell[a]) * delta[a];
        } else {
            step[a] = 0;
            delta[a] = std::numeric_limits<double>::infinity();
            next[a] = std::numeric_limits<double>::infinity();
        }
    }
    double t = t0;
    while (t < t1) {
        const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
        const double t_exit = std::min(next[a], t1);
        const double maj = m.density_scale * m.cell_at(cell[0], cell[1], cell[2]);
        if (maj > 0.0 && t_exit > t) {
            if (!out.empty() && out.back().t1 == t && out.back().majorant == maj)
                out.back().t1 = t_exit;
            else
                out.push_back({t, t_exit, maj});
        }
        t = t_exit;
        cell[a] += step[a];
        if (cell[a] < 0 || cell[a] >= m.n[a]) break;
        next[a] += delta[a];
    }
}

double VdbClouds::feature_size_m() const { return impl_->voxel_size_m; }
std::uint64_t VdbClouds::active_voxel_count() const { return impl_->grid->activeVoxelCount(); }
std::uint64_t VdbClouds::negative_voxel_count() const { return impl_->negatives; }
std::uint64_t VdbClouds::memory_bytes() const { return impl_->memory; }
double VdbClouds::max_value() const { return impl_->max_value; }
std::string VdbClouds::warning() const {
    if (impl_->negatives == 0) return {};
    return fmt::format("{}: {} negative densities were set to 0", impl_->where(), impl_->negatives);
}

glm::dvec3 VdbClouds::world_bounds_min() const {
    const Impl& m = *impl_;
    glm::dvec3 lo(std::numeric_limits<double>::infinity());
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 ip(m.origin.x() + ((c & 1) ? m.n[0] * m.cell : 0),
                            m.origin.y() + ((c & 2) ? m.n[1] * m.cell : 0),
                            m.origin.z() + ((c & 4) ? m.n[2] * m.cell : 0));
        lo = glm::min(lo, glm::dvec3(m.index_to_world * glm::dvec4(ip, 1.0)));
    }
    return lo;
}
glm::dvec3 VdbClouds::world_bounds_max() const {
    const Impl& m = *impl_;
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 ip(m.origin.x() + ((c & 1) ? m.n[0] * m.cell : 0),
                            m.origin.y() + ((c & 2) ? m.n[1] * m.cell : 0),
                            m.origin.z() + ((c & 4) ? m.n[2] * m.cell : 0));
        hi = glm::max(hi, glm::dvec3(m.index_to_world * glm::dvec4(ip, 1.0)));
    }
    return hi;
}

}  // namespace welkin
