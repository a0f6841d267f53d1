// SPDX-License-Identifier: Apache-2.0
// Clouds from an OpenVDB file: a Blender volume object's grid as a cloud density source.
//
// Blender's Python cannot read voxels, so the core opens the .vdb file itself with
// OpenVDB (Museth 2013, "VDB: High-resolution sparse volumes with dynamic topology", ACM
// TOG 32(3)). A point p of Blender's world frame maps to the grid's index space through the
// object's world transform (Blender's Object.matrix_world, object -> world) and the grid's
// own transform (index -> object, stored in the file):
//     index = grid_transform^-1 (matrix_world^-1 p),
// and sigma_t(p) = density_scale * trilinear(grid, index - offset), the values interpolated
// between voxel centres (openvdb::tools::BoxSampler). Both transforms are affine, so a ray
// maps to a ray and keeps its parameter t (world metres): empty space is skipped in index
// space.
//
// Voxel placement (where voxel ijk's value sits). OpenVDB's convention puts it at index
// point ijk (offset 0: VoxelPlacement::OpenVdb). Blender 3.4 / Cycles render it half a voxel
// further along every index axis, at index point ijk + (1/2, 1/2, 1/2) (offset 1/2:
// VoxelPlacement::Blender, the default, so that a Welkin cloud sits where Blender shows the
// volume object). The offsets measured against Cycles are in docs/validation.md
// ("Clouds against Cycles", bench/cycles_volume.py). The offset is applied once, to the index -> world
// map (index_to_world = matrix_world * grid_transform * translate(offset)), so sigma_t, the
// majorant DDA and world_bounds_* all move together and empty-space skipping stays
// conservative. For a grid transform of scale s (and no rotation) this is the world
// translation +s/2 per axis that bench/cycles_volume.py used to add to matrix_world.
//
// Empty-space skipping. At load, the grid's active voxels and tiles (the tree's occupied
// leaf nodes and tiles) are binned into a coarse majorant grid: cells of 8 voxels (one
// leaf node; larger for grids over 64 leaves across, at most 64^3 cells), each holding the
// largest value that can reach it by interpolation (the cell's own maximum, then dilated
// by one cell). A ray walks these cells with a 3D DDA (Amanatides & Woo 1987, "A fast voxel
// traversal algorithm for ray tracing", Eurographics) and reports the non-empty ones as
// majorant segments: the fast march steps only through them, the path tracer samples
// free paths against their majorants (pbrt-v4's majorant grid, ch. 11.4).
//
// Bad input. Every error names the file and the grid:
//   * missing file, unreadable or corrupt file          -> welkin::IoError;
//   * no grid of that name (the message lists the file's grids), a grid that is not a
//     FloatGrid, an empty grid (no active voxels), a non-zero background (fog volumes
//     have background 0; anything else would fill all of space), non-finite values,
//     a non-affine (frustum) transform, a singular matrix_world, a grid whose memory
//     (from the file's metadata, before any voxel is read) exceeds max_memory_bytes,
//     a grid whose active voxels reach beyond kMaxVdbCoordinate of the origin or span more
//     than kMaxVdbExtent voxels along an axis (checked on the file's metadata before the
//     tree is read, and again on the tree)            -> welkin::InvalidArgument;
//   * memory running out while the grid is read (a corrupt tree) -> welkin::OutOfMemory
//     (a std::bad_alloc naming the file).
// The limits are documented in docs/limits.md.
//   * negative values (densities cannot be negative): with Negative::Clamp (the default)
//     they are set to 0 and counted (negative_voxel_count(), warning()); with
//     Negative::Reject they are an InvalidArgument.
// Nothing is partly constructed: a VdbClouds either holds a valid grid or was not made.
//
// Thread safety: immutable after construction; sigma_t uses its own (unregistered) value
// accessor per call, so any number of threads may query at once.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <glm/mat4x4.hpp>

#include "welkin/clouds/density.hpp"

namespace welkin {

// Index coordinates of active voxels lie within [-kMaxVdbCoordinate, kMaxVdbCoordinate],
// and their bounding box spans at most kMaxVdbExtent voxels along each axis.
inline constexpr int kMaxVdbCoordinate = 1 << 24;
inline constexpr int kMaxVdbExtent = 1 << 20;

struct VdbCloudOptions {
    std::string grid = "density";
    // Blender's matrix_world (object -> world), glm layout (column-major: m[col][row]).
    glm::dmat4 matrix_world{1.0};
    double density_scale = 1.0;  // sigma_t per unit grid value, m^-1, [0, 1e6]
    enum class Negative { Clamp, Reject };
    Negative negative = Negative::Clamp;
    // Where voxel ijk's value sits in index space: Blender (ijk + 1/2, as Cycles 3.4 renders
    // it; the default) or OpenVdb (ijk, OpenVDB's own convention). See the file comment.
    enum class VoxelPlacement { Blender, OpenVdb };
    VoxelPlacement placement = VoxelPlacement::Blender;
    // Refuse grids larger than this in memory (the file's own estimate), bytes, >= 1.
    std::uint64_t max_memory_bytes = std::uint64_t(4) << 30;
};

class VdbClouds final : public CloudDensity {
public:
    VdbClouds(const std::string& path, const VdbCloudOptions& options = {});
    ~VdbClouds() override;

    double sigma_t(const glm::dvec3& p) const override;
    void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const override;
    double feature_size_m() const override;

    std::uint64_t active_voxel_count() const;
    std::uint64_t negative_voxel_count() const;
    std::uint64_t memory_bytes() const;  // the grid's in-memory size
    std::string warning() const;         // empty, or what was clamped
    double max_value() const;            // largest grid value (after clamping)
    // World-space axis-aligned bounds of the grid's support (m).
    glm::dvec3 world_bounds_min() const;
    glm::dvec3 world_bounds_max() const;

private:
    void load(const std::string& path, const VdbCloudOptions& options);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace welkin
