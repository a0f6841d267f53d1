// SPDX-License-Identifier: Apache-2.0
// A lazily filled, sparse, multi-resolution grid of cloud optical depth towards a light.
//
// The fast march (clouds/lighting.hpp) needs, at every lit sample x, the cloud's optical
// depth towards the sun, tau(x) = integral_0^D sigma_t(x + l s) dl. Marching a shadow ray
// per sample costs light_steps density lookups each time, and neighbouring samples (of the
// same ray and of neighbouring rays) march nearly the same ray. tau is a continuous
// function of x (an integral of a bounded density along a fixed direction), so it can be
// tabulated on a grid and interpolated trilinearly, the "deep shadow map" / shadow volume
// of production volume renderers (Lokovic & Veach 2000, "Deep shadow maps", SIGGRAPH;
// Hillaire 2016, "Physically based sky, atmosphere and cloud rendering in Frostbite",
// sec. 5.8, whose volumetric shadow map stores the same optical depth along the sun).
//
// Layout. World-space cubic cells of edge h_L = h_0 2^L (level L = 0..kMaxLevels-1),
// grouped in tiles of kTile^3 cells holding their (kTile + 1)^3 corner vertices (a cell's
// eight corners are always in one tile; the faces shared by two tiles are stored twice).
// A tile is allocated the first time a lookup reaches it, and each vertex is computed the
// first time a lookup needs it (NaN marks "not yet"): only the part of space the view
// rays touch is ever filled, which for a layer seen from the ground is a small part of
// its (unbounded) shell, and for a VDB a part of its bounding box.
//
// Level of detail. A lookup names the length it resolves (the view step): it reads the
// coarsest level whose cell is no longer than that, h_L <= footprint < h_{L+1} (h_0 for
// shorter footprints). Far samples of a sky, taken a kilometre apart along grazing rays,
// read cells of that size; near ones read h_0.
//
// Vertex values: tau from the vertex position along direction(vertex) over at most
// max_distance_m, by the midpoint rule with `steps` steps spread over the density's
// majorant segments (the same quadrature the per-sample shadow march uses). direction()
// may depend on the point (the local zenith of a curved planet) or be constant (the sun).
//
// Determinism. A vertex's value is a pure function of its level and index; whichever
// thread computes it first, and however often a race makes two threads compute it, the
// stored float is the same. Lookups are therefore independent of the thread count and
// of the order of the rays. Thread safety: any number of threads may call tau() at once
// (tiles are published with an atomic compare-and-swap, vertices with relaxed atomic
// stores of identical values).
//
// Accuracy: trilinear interpolation of tau; the error is second order in h (tau's
// curvature across a cell). The cost: one vertex march per vertex touched, shared by every
// sample in the eight cells around it.
//
// Aligned to a constant direction (the sun, and the other straight lines of the fast
// march). When the direction w is the same everywhere, the grid's axes are turned so that
// its third axis is w (the first two any orthonormal pair across it): the vertices
// (i, j, k), (i, j, k + 1), ... then lie on one line along w, a cell edge h apart, and
// share their march. A line is cut into blocks of B = ceil(q) + 1 cells (q = D / h, D =
// max_distance_m), and each vertex stores the optical depth from it to the end of its
// block, C(k) = integral of sigma_t(x_k + l w) dl up to the block's last vertex, by the
// recurrence
//
//     C(k) = integral over the cell [x_k, x_{k+1}] + C(k + 1),   C = 0 at the block's end,
//
// walked from the first vertex already known (or the block's end, or the line's last
// segment, beyond which C = 0) back to the one asked for; the blocks bound a walk (a line
// towards a low sun crosses a layer over tens to hundreds of kilometres, of which a vertex
// needs D): a vertex costs the samples of one cell edge instead of
// a march of `steps` samples over max_distance_m (the "incremental" form of a shadow
// volume along the light, as in the sun-aligned slices of Lokovic & Veach's deep shadow
// maps). The optical depth over at most D is then a difference on the same line,
// tau(x_k) = C(k) - C(x_k + D w) when x_k + D w is in the same block, else
// C(k) + C(first vertex of the next block) - C(x_k + D w), C between vertices linear along
// the line (exact on a piecewise-constant line, and no interpolation across lines, so the
// shadow is not blurred along the walk). The cell's integral: the midpoint
// rule over each part of [x_k, x_{k+1}] inside the density's majorant segments (taken from
// the first vertex of the vertex's tile along w), in steps no longer than
// min(h, max_distance_m / steps): at the finest levels one density lookup per cell, far
// finer along w than the `steps` samples a vertex's own march spreads over max_distance_m,
// and never coarser than that march at the coarse levels. Each value depends only on the
// line, its block and its own tile's base vertex, so the stored values are the same
// whichever thread walks first (C is published with release stores: a value seen implies
// every value after it in its block is visible, which is what lets an unset value after a
// known one in the same block read as 0).
//
// Near field (aligned grids, set_near_field(levels, steps), off by default). A lookup on
// level L reads the grid `levels` coarser, L' = L + levels, at the point one cell of L'
// further along w, and adds the first cell's depth marched at the lookup's own point (the
// midpoint rule over the density's majorant segments, steps no longer than d / `steps`): tau(x) =
// integral_0^d sigma_t(x + l w) dl + tau'(x + d w), d = h_{L'}, the vertices of L' holding their depth over
// max_distance_m - h_{L'}. The shadow's detail next to x (a lit face, the edge of a wisp) is marched exactly,
// the depth from farther away is read on cells 2^levels times as wide, whose vertices the neighbouring rays
// share (a ray's samples each touch new vertices when the rays are a cell apart, as an image's pixels are at
// the footprint's level). A lookup may decline it (denser rays share the vertices of their
// own level): it then reads its own level, whose vertices, set for the near field, reach
// max_distance_m less one cell of that level.
//
// Chord (set_chord_scaled, off by default). tau has a kink wherever its line leaves the
// cloud through a face of the density's majorant segments (a layer's flat base seen along
// the direction away from the sun): trilinear interpolation across that kink errs by up to
// a quarter of a cell's depth, and on a grid turned to the direction, whose cells the face
// cuts at a slant, the error depends on where each line of vertices meets the face and
// beats into streaks along it (an even deck from below). With the chord, a vertex stores
// tau over the length l of the segments on its line within its reach, the mean extinction
// tau / l, and a lookup returns l(p), exact from the segments, times the trilinear
// interpolation of that mean over the corners whose l is positive (weights renormalised;
// a point whose corners all lie outside marches its own line). On an even deck the mean
// is the deck's extinction on every line, and the face's kink is in l alone: the lookup
// is exact across it.
//
// Cross spacing (aligned grids, set_cross_spacing; 1 and 1 by default). The lines of
// vertices may lie closer or farther apart across the direction than a cell along it: the
// vertex (i, j, k) at h (i c_1 e_1 + j c_2 e_2 + k w), e_1 the horizontal normal to w (x
// when w is vertical) and e_2 = w x e_1. A quantity that varies slowly along one axis
// across the lines and fast along the other is read on lines spaced for each (the sides'
// chord across the sun line, clouds/lighting.cpp: a horizontal line's depth changes over
// a few metres up a deck's base, over kilometres along the ground; the depth towards a low
// sun, which changes faster up the cloud than across the ground).
//
// Both ways (aligned grids, set_both_ways, off by default). The depth over the whole chord
// through x along the line, from x - D w to x + D w: the same walks read over the span
// [k - q, k + q] of a vertex's line (C at both ends, linear between vertices, summed over
// the blocks the span crosses), where two grids along w and -w would each walk the line.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/clouds/density.hpp"

namespace welkin {

// Optical depth of the cloud along [0, max_distance] of `ray`, by the midpoint rule with
// `steps` steps spread over the majorant segments in proportion to their length (each
// segment gets a whole number of equal steps). `segs` is scratch.
double march_optical_depth(const CloudDensity& density, const CloudRay& ray, double max_distance, int steps,
                           std::vector<MajorantSegment>& segs);

class OpticalDepthGrid {
public:
    static constexpr int kTile = 8;        // cells per tile edge
    static constexpr int kMaxLevels = 16;  // h_0 .. h_0 2^15
    using Direction = std::function<glm::dvec3(const glm::dvec3&)>;

    // The density must outlive the grid. base_spacing_m > 0 (h_0), max_distance_m > 0,
    // steps >= 1. A direction that depends on the point: a march per vertex.
    OpticalDepthGrid(const CloudDensity& density, Direction direction, double base_spacing_m,
                     double max_distance_m, int steps);
    // A constant direction (normalised here; zero or non-finite is InvalidArgument
    // "direction"): the grid aligned with it, its lines of vertices sharing one walk (above).
    OpticalDepthGrid(const CloudDensity& density, const glm::dvec3& direction, double base_spacing_m,
                     double max_distance_m, int steps);
    ~OpticalDepthGrid();
    OpticalDepthGrid(const OpticalDepthGrid&) = delete;
    OpticalDepthGrid& operator=(const OpticalDepthGrid&) = delete;

    struct Tile;
    // Per-thread scratch: a small direct-mapped cache of tiles (the lookups of one ray and
    // its neighbours reuse a few tiles) and the segment buffer of vertex marches.
    struct Cursor {
        static constexpr int kSlots = 32;
        std::uint64_t key[kSlots];
        Tile* tile[kSlots] = {};
        std::vector<MajorantSegment> segs;
        // The aligned grid's walks: their own cache (a line crosses other tiles than the
        // lookups around it) and the vertices of the walk under way.
        std::uint64_t walk_key[kSlots];
        Tile* walk_tile[kSlots] = {};
        struct Step {
            Tile* tile;
            int index;
            double local;
        };
        std::vector<Step> run;
        Cursor() {
            std::fill(key, key + kSlots, ~std::uint64_t(0));
            std::fill(walk_key, walk_key + kSlots, ~std::uint64_t(0));
        }
    };

    // The level whose cell is the largest power-of-two multiple of h_0 not above footprint.
    int level_for(double footprint_m) const;
    double spacing_m(int level) const { return h0_ * double(std::uint64_t(1) << level); }

    // Interpolated optical depth at world point p on `level`; with the near field set,
    // near_field false reads `level` itself (its vertices reaching max_distance_m less a cell).
    double tau(const glm::dvec3& p, int level, Cursor& cursor, bool near_field = true) const;

    // The optical depth straight from a march of `steps` samples over max_distance_m (what
    // a vertex of a point-dependent grid stores, at any point; both ways, one march each way).
    double march(const glm::dvec3& p, std::vector<MajorantSegment>& segs) const;

    // The near field (above): levels in [0, kMaxLevels) (0: off), steps in [1, 64]; for an
    // aligned grid only, set before the first lookup (InvalidArgument otherwise).
    void set_near_field(int levels, int steps);
    // Interpolate the mean extinction along the line, not the depth (above, "Chord"); set
    // before the first lookup (InvalidArgument "chord" otherwise).
    void set_chord_scaled(bool on);
    // The lines' spacing across the direction (above, "Cross spacing"): `first` and `second`
    // cells of the level along the frame's first and second axes, each in [1/64, 64]; an
    // aligned grid only, set before the first lookup (InvalidArgument "cross_spacing").
    void set_cross_spacing(double first, double second);
    // The depth both ways along the line (above, "Both ways"): an aligned grid without a
    // near field only, set before the first lookup (InvalidArgument "both_ways" otherwise).
    void set_both_ways(bool on);
    // Whether the grid is aligned with a constant direction (the second constructor).
    bool aligned() const { return aligned_; }
    // The world position of vertex (i, j, k) of `level` (the aligned frame's axes or x, y, z).
    glm::dvec3 vertex_position(int level, std::int64_t i, std::int64_t j, std::int64_t k) const;

private:
    Tile* find(std::uint64_t key) const;
    // The tile of tile coordinates t on `level` through the cache (key, tile), made if absent
    // when `make`, else null if absent.
    Tile* tile_at(int level, const std::int64_t t[3], std::uint64_t* keys, Tile** tiles, bool make) const;
    // The aligned grid: a vertex's optical depth over max_distance_m, and the cumulative C.
    double aligned_vertex(int level, const std::int64_t v[3], Cursor& cursor) const;
    double cumulative(int level, const std::int64_t v[3], std::int64_t block, Cursor& cursor) const;
    float stored_cumulative(int level, const std::int64_t v[3], Cursor& cursor) const;

    const CloudDensity& density_;
    Direction direction_;
    double h0_, max_distance_m_;
    int steps_;
    bool aligned_ = false;
    int near_levels_ = 0, near_steps_ = 2;
    bool chord_ = false, both_ways_ = false;
    double march_at(const glm::dvec3& p, double reach, std::vector<MajorantSegment>& segs) const;
    // The aligned grid: the depth over [v - back, v + ahead] cells along vertex v's line.
    double aligned_span(int level, const std::int64_t v[3], double back, double ahead, Cursor& cursor) const;
    // The length of the density's majorant segments along direction(p) over [0, reach].
    double chord(const glm::dvec3& p, double reach, std::vector<MajorantSegment>& segs) const;
    double grid_tau(const glm::dvec3& p, int level, Cursor& cursor) const;
    glm::dvec3 axis_[3];                 // the aligned frame: axis_[2] the direction
    double cross_[3] = {1.0, 1.0, 1.0};  // the vertex spacing along each axis, in cells
    struct Map;
    std::unique_ptr<Map> map_;
};

}  // namespace welkin
