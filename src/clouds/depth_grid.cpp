// SPDX-License-Identifier: Apache-2.0
// A lazily filled grid of cloud optical depth; see clouds/depth_grid.hpp.
#include "welkin/clouds/depth_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/concurrent_unordered_map.h>

#include "welkin/base/error.hpp"
#include "welkin/base/rng.hpp"

namespace welkin {

double march_optical_depth(const CloudDensity& density, const CloudRay& ray, double max_distance, int steps,
                           std::vector<MajorantSegment>& segs) {
    density.segments(ray, max_distance, segs);
    double total = 0.0;
    for (const auto& s : segs) total += s.t1 - s.t0;
    if (!(total > 0.0)) return 0.0;
    const double dt = total / steps;
    double tau = 0.0;
    for (const auto& s : segs) {
        const int n = std::max(1, int(std::ceil((s.t1 - s.t0) / dt - 1e-9)));
        const double h = (s.t1 - s.t0) / n;
        for (int k = 0; k < n; ++k) tau += density.sigma_t(ray.at(s.t0 + (k + 0.5) * h)) * h;
    }
    return tau;
}

namespace {

constexpr int kV = OpticalDepthGrid::kTile + 1;  // vertices per tile edge
constexpr int kCoordBits = 20;                   // signed tile coordinates per axis
constexpr std::int64_t kCoordHalf = std::int64_t(1) << (kCoordBits - 1);

}  // namespace

struct OpticalDepthGrid::Tile {
    int level;
    std::int64_t origin[3];  // vertex index of the tile's first corner on its level
    std::atomic<float> v[kV * kV * kV];
    Tile(int l, const std::int64_t o[3]) : level(l), origin{o[0], o[1], o[2]} {
        for (auto& x : v) x.store(std::numeric_limits<float>::quiet_NaN(), std::memory_order_relaxed);
    }
};

// The tile key's bits hashed (splitmix64's finaliser): std::hash of an integer is the
// integer itself, and the map's buckets are the low bits of the hash, here the tile's z
// coordinate, which takes a handful of values over a cloud layer (a shell a few tiles
// thick): every tile of a layer would share a few buckets, and a lookup would walk them.
struct TileKeyHash {
    std::size_t operator()(std::uint64_t key) const { return std::size_t(splitmix64_mix(key)); }
};

struct OpticalDepthGrid::Map {
    tbb::concurrent_unordered_map<std::uint64_t, std::unique_ptr<Tile>, TileKeyHash> tiles;
};

OpticalDepthGrid::OpticalDepthGrid(const CloudDensity& density, Direction direction, double base_spacing_m,
                                   double max_distance_m, int steps)
    : density_(density),
      direction_(std::move(direction)),
      h0_(base_spacing_m),
      max_distance_m_(max_distance_m),
      steps_(steps),
      map_(std::make_unique<Map>()) {
    if (!(h0_ > 0.0 && std::isfinite(h0_)))
        throw InvalidArgument("base_spacing_m", "must be a finite positive length");
    if (!(max_distance_m_ > 0.0)) throw InvalidArgument("max_distance_m", "must be positive");
    require_in_range("steps", steps_, 1, 1 << 16);
}

OpticalDepthGrid::~OpticalDepthGrid() = default;

int OpticalDepthGrid::level_for(double footprint_m) const {
    if (!(footprint_m > h0_)) return 0;
    return std::clamp(int(std::floor(std::log2(footprint_m / h0_))), 0, kMaxLevels - 1);
}

double OpticalDepthGrid::march(const glm::dvec3& p, std::vector<MajorantSegment>& segs) const {
    return march_optical_depth(density_, {p, direction_(p)}, max_distance_m_, steps_, segs);
}

OpticalDepthGrid::Tile* OpticalDepthGrid::find(std::uint64_t key) const {
    auto it = map_->tiles.find(key);
    return it == map_->tiles.end() ? nullptr : it->second.get();
}

double OpticalDepthGrid::tau(const glm::dvec3& p, int level, Cursor& cursor) const {
    const double h = spacing_m(level);
    double w[3];
    std::int64_t base[3], tcoord[3];
    for (int a = 0; a < 3; ++a) {
        const double u = p[a] / h;
        const double b = std::floor(u);
        w[a] = u - b;
        base[a] = std::int64_t(b);
        // Tile of the cell (floor division), within the key's range; else march directly.
        tcoord[a] = base[a] >= 0 ? base[a] / kTile : -((-base[a] + kTile - 1) / kTile);
        if (!(std::abs(b) < 1e15) || tcoord[a] <= -kCoordHalf || tcoord[a] >= kCoordHalf - 1)
            return march(p, cursor.segs);
    }
    const std::uint64_t key = (std::uint64_t(level) << (3 * kCoordBits)) |
                              (std::uint64_t(tcoord[0] + kCoordHalf) << (2 * kCoordBits)) |
                              (std::uint64_t(tcoord[1] + kCoordHalf) << kCoordBits) |
                              std::uint64_t(tcoord[2] + kCoordHalf);
    const int slot = int((key ^ (key >> 20) ^ (key >> 40)) & (Cursor::kSlots - 1));
    if (key != cursor.key[slot]) {
        Tile* t = find(key);
        if (!t) {
            const std::int64_t origin[3] = {tcoord[0] * kTile, tcoord[1] * kTile, tcoord[2] * kTile};
            auto fresh = std::make_unique<Tile>(level, origin);
            // Whoever inserts first wins; the loser's empty tile is dropped.
            t = map_->tiles.emplace(key, std::move(fresh)).first->second.get();
        }
        cursor.key[slot] = key;
        cursor.tile[slot] = t;
    }
    Tile& t = *cursor.tile[slot];
    const int li = int(base[0] - t.origin[0]), lj = int(base[1] - t.origin[1]),
              lk = int(base[2] - t.origin[2]);
    double corner[8];
    for (int c = 0; c < 8; ++c) {
        const int i = li + (c & 1), j = lj + ((c >> 1) & 1), k = lk + ((c >> 2) & 1);
        std::atomic<float>& vertex = t.v[(k * kV + j) * kV + i];
        float v = vertex.load(std::memory_order_relaxed);
        if (std::isnan(v)) {
            const glm::dvec3 x(double(t.origin[0] + i) * h, double(t.origin[1] + j) * h,
                               double(t.origin[2] + k) * h);
            v = float(march(x, cursor.segs));
            vertex.store(v, std::memory_order_relaxed);
        }
        corner[c] = v;
    }
    const auto lerp = [](double a, double b, double s) { return a + s * (b - a); };
    const double x00 = lerp(corner[0], corner[1], w[0]), x10 = lerp(corner[2], corner[3], w[0]);
    const double x01 = lerp(corner[4], corner[5], w[0]), x11 = lerp(corner[6], corner[7], w[0]);
    return lerp(lerp(x00, x10, w[1]), lerp(x01, x11, w[1]), w[2]);
}

}  // namespace welkin
