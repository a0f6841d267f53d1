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
    // steps >= 1.
    OpticalDepthGrid(const CloudDensity& density, Direction direction, double base_spacing_m,
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
        Cursor() { std::fill(key, key + kSlots, ~std::uint64_t(0)); }
    };

    // The level whose cell is the largest power-of-two multiple of h_0 not above footprint.
    int level_for(double footprint_m) const;
    double spacing_m(int level) const { return h0_ * double(std::uint64_t(1) << level); }

    // Interpolated optical depth at world point p on `level`.
    double tau(const glm::dvec3& p, int level, Cursor& cursor) const;

    // The optical depth straight from a march (what a vertex stores, at any point).
    double march(const glm::dvec3& p, std::vector<MajorantSegment>& segs) const;

private:
    Tile* find(std::uint64_t key) const;

    const CloudDensity& density_;
    Direction direction_;
    double h0_, max_distance_m_;
    int steps_;
    struct Map;
    std::unique_ptr<Map> map_;
};

}  // namespace welkin
