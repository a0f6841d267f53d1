// Clouds from an OpenVDB file; see vdb_clouds.hpp.
#include "welkin/clouds/vdb.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <vector>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

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
};

namespace {

void initialize_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

std::uint64_t metadata_u64(const openvdb::GridBase& meta, const char* name) {
    if (const auto v = meta.getMetadata<openvdb::Int64Metadata>(name)) return std::uint64_t(std::max<openvdb::Int64>(0, v->value()));
    return 0;
}

}  // namespace

VdbClouds::VdbClouds(const std::string& path, const VdbCloudOptions& options) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.path = path;
    m.grid_name = options.grid;
    require_in_range("density_scale", options.density_scale, 0.0, 1e6, "m^-1");
    if (options.max_memory_bytes < 1) throw InvalidArgument("max_memory_bytes", "must be at least 1");
    if (options.grid.empty()) throw InvalidArgument("grid", fmt::format("must name a grid of VDB file '{}', got an empty name", path));
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) require_finite(fmt::format("matrix_world[{}][{}]", r, c), options.matrix_world[c][r]);
    m.density_scale = options.density_scale;
    initialize_openvdb();

    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(fmt::format("VDB file '{}' (grid '{}'): no such file", path, options.grid));

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
    } catch (const std::exception& e) {
        throw IoError(fmt::format("VDB file '{}' (grid '{}'): cannot be read as OpenVDB: {}", path, options.grid, e.what()));
    }
    if (!meta->isType<openvdb::FloatGrid>())
        throw InvalidArgument("grid", fmt::format("{} is of type '{}'; Welkin reads float grids (FloatGrid) only",
                                                  m.where(), meta->type()));
    // The memory estimate comes from the file's metadata, before any voxel is read.
    const std::uint64_t mem = metadata_u64(*meta, openvdb::GridBase::META_FILE_MEM_BYTES);
    const std::uint64_t voxels = metadata_u64(*meta, openvdb::GridBase::META_FILE_VOXEL_COUNT);
    const std::uint64_t estimate = std::max(mem, voxels * sizeof(float));
    if (estimate > options.max_memory_bytes)
        throw InvalidArgument("max_memory_bytes",
                              fmt::format("{} needs about {:.1f} MiB ({} active voxels), more than the limit of {:.1f} MiB",
                                          m.where(), estimate / 1048576.0, voxels, options.max_memory_bytes / 1048576.0));
    try {
        m.grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(options.grid));
        file.close();
    } catch (const std::exception& e) {
        throw IoError(fmt::format("{}: cannot be read (corrupt data?): {}", m.where(), e.what()));
    }
    if (!m.grid) throw InvalidArgument("grid", fmt::format("{} is not a FloatGrid", m.where()));
    m.memory = m.grid->memUsage();
    if (m.memory > options.max_memory_bytes)
        throw InvalidArgument("max_memory_bytes", fmt::format("{} takes {:.1f} MiB, more than the limit of {:.1f} MiB",
                                                              m.where(), m.memory / 1048576.0,
                                                              options.max_memory_bytes / 1048576.0));
    if (m.grid->activeVoxelCount() == 0)
        throw InvalidArgument("grid", fmt::format("{} is empty (no active voxels)", m.where()));
    const float background = m.grid->background();
    if (background != 0.0f)
        throw InvalidArgument("grid", fmt::format("{} has background value {}; a density grid must have background 0 "
                                                  "(a fog volume), or it would fill all of space", m.where(), background));
    if (!m.grid->transform().isLinear())
        throw InvalidArgument("grid", fmt::format("{} has a non-affine (frustum) transform, which Welkin does not read",
                                                  m.where()));

    // Values: non-finite ones are rejected, negative ones clamped (and counted) or rejected.
    for (auto it = m.grid->beginValueOn(); it; ++it) {
        const float v = *it;
        if (!std::isfinite(v))
            throw InvalidArgument("grid", fmt::format("{} holds a non-finite value at {}", m.where(), it.getCoord().asVec3i().str()));
        if (v < 0.0f) {
            if (options.negative == VdbCloudOptions::Negative::Reject)
                throw InvalidArgument("grid", fmt::format("{} holds a negative density {} at {} (densities must be >= 0; "
                                                          "the Clamp policy sets them to 0)",
                                                          m.where(), v, it.getCoord().asVec3i().str()));
            m.negatives += it.isVoxelValue() ? 1 : it.getVoxelCount();
            it.setValue(0.0f);
        } else {
            m.max_value = std::max(m.max_value, v);
        }
    }

    // Transforms: index -> object from the file (OpenVDB's Mat4d acts on row vectors,
    // p' = p M, so its transpose is glm's column-vector matrix), then object -> world.
    const openvdb::Mat4d vm = m.grid->transform().baseMap()->getAffineMap()->getMat4();
    glm::dmat4 index_to_object;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) index_to_object[c][r] = vm(c, r);
    // The voxel placement (see the header): Blender's puts voxel ijk's value at index point
    // ijk + 1/2, i.e. the grid's index frame is translated by +1/2 before its transform.
    const double offset = options.placement == VdbCloudOptions::VoxelPlacement::Blender ? 0.5 : 0.0;
    const glm::dmat4 placement = glm::translate(glm::dmat4(1.0), glm::dvec3(offset));
    m.index_to_world = options.matrix_world * index_to_object * placement;
    const double det = glm::determinant(glm::dmat3(m.index_to_world));
    if (!(std::abs(det) > 1e-30) || !std::isfinite(det))
        throw InvalidArgument("matrix_world", fmt::format("maps {} to a degenerate (singular) volume", m.where()));
    m.world_to_index = glm::inverse(m.index_to_world);
    m.voxel_size_m = std::cbrt(std::abs(det));

    // The majorant grid over the active bounding box, one voxel of margin for interpolation.
    openvdb::CoordBBox box = m.grid->evalActiveVoxelBoundingBox();
    box.expand(1);
    const openvdb::Coord extent = box.dim();
    const int largest = std::max({extent.x(), extent.y(), extent.z()});
    m.cell = std::max(8, (largest + 63) / 64);
    m.origin = box.min();
    for (int a = 0; a < 3; ++a) m.n[a] = (extent[a] + m.cell - 1) / m.cell;
    m.majorant.assign(std::size_t(m.n[0]) * m.n[1] * m.n[2], 0.0f);
    const auto cell_of = [&](int a, int i) { return std::clamp((i - m.origin[a]) / m.cell, 0, m.n[a] - 1); };
    for (auto it = m.grid->cbeginValueOn(); it; ++it) {
        const float v = *it;
        if (!(v > 0.0f)) continue;
        openvdb::CoordBBox b;
        it.getBoundingBox(b);
        for (int k = cell_of(2, b.min().z()); k <= cell_of(2, b.max().z()); ++k)
            for (int j = cell_of(1, b.min().y()); j <= cell_of(1, b.max().y()); ++j)
                for (int i = cell_of(0, b.min().x()); i <= cell_of(0, b.max().x()); ++i)
                    m.cell_at(i, j, k) = std::max(m.cell_at(i, j, k), v);
    }
    // Dilate by one cell: a voxel next to a cell's face reaches into it by interpolation.
    std::vector<float> own = m.majorant;
    for (int k = 0; k < m.n[2]; ++k)
        for (int j = 0; j < m.n[1]; ++j)
            for (int i = 0; i < m.n[0]; ++i) {
                float v = 0.0f;
                for (int dk = -1; dk <= 1; ++dk)
                    for (int dj = -1; dj <= 1; ++dj)
                        for (int di = -1; di <= 1; ++di) {
                            const int ii = i + di, jj = j + dj, kk = k + dk;
                            if (ii < 0 || jj < 0 || kk < 0 || ii >= m.n[0] || jj >= m.n[1] || kk >= m.n[2]) continue;
                            v = std::max(v, own[(std::size_t(kk) * m.n[1] + jj) * m.n[0] + ii]);
                        }
                m.cell_at(i, j, k) = v;
            }
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
        const glm::dvec3 ip(m.origin.x() + ((c & 1) ? m.n[0] * m.cell : 0), m.origin.y() + ((c & 2) ? m.n[1] * m.cell : 0),
                            m.origin.z() + ((c & 4) ? m.n[2] * m.cell : 0));
        lo = glm::min(lo, glm::dvec3(m.index_to_world * glm::dvec4(ip, 1.0)));
    }
    return lo;
}
glm::dvec3 VdbClouds::world_bounds_max() const {
    const Impl& m = *impl_;
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 ip(m.origin.x() + ((c & 1) ? m.n[0] * m.cell : 0), m.origin.y() + ((c & 2) ? m.n[1] * m.cell : 0),
                            m.origin.z() + ((c & 4) ? m.n[2] * m.cell : 0));
        hi = glm::max(hi, glm::dvec3(m.index_to_world * glm::dvec4(ip, 1.0)));
    }
    return hi;
}

}  // namespace welkin
