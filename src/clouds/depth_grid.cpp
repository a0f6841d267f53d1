// SPDX-License-Identifier: Apache-2.0
// A lazily filled grid of cloud optical depth; see clouds/depth_grid.hpp.
#include "welkin/clouds/depth_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/concurrent_unordered_map.h>

#include "welkin/base/error.hpp"
#include "welkin/base/rng.hpp"

namespace welkin {

namespace {

// The midpoint rule for the optical depth along `ray` over the parts of [a, b] inside the
// majorant segments, each part in equal steps no longer than max_step (exact on a constant
// density).
double midpoint_depth(const CloudDensity& density, const CloudRay& ray,
                      const std::vector<MajorantSegment>& segs, double a, double b, double max_step) {
    double tau = 0.0;
    for (const auto& s : segs) {
        const double t0 = std::max(s.t0, a), t1 = std::min(s.t1, b);
        if (!(t1 > t0)) continue;
        const int n = std::max(1, int(std::ceil((t1 - t0) / max_step - 1e-9)));
        const double h = (t1 - t0) / n;
        for (int k = 0; k < n; ++k) tau += density.sigma_t(ray.at(t0 + (k + 0.5) * h)) * h;
    }
    return tau;
}

}  // namespace

double march_optical_depth(const CloudDensity& density, const CloudRay& ray, double max_distance, int steps,
                           std::vector<MajorantSegment>& segs) {
    density.segments(ray, max_distance, segs);
    double total = 0.0;
    for (const auto& s : segs) total += s.t1 - s.t0;
    if (!(total > 0.0)) return 0.0;
    return midpoint_depth(density, ray, segs, 0.0, max_distance, total / steps);
}

namespace {

constexpr int kV = OpticalDepthGrid::kTile + 1;  // vertices per tile edge
constexpr int kCoordBits = 20;                   // signed tile coordinates per axis
constexpr std::int64_t kCoordHalf = std::int64_t(1) << (kCoordBits - 1);
// How far along its line an aligned grid's cumulative depth looks: past any layer's or
// volume's far side (a shell 20 km up spans under 1100 km of a 6360 km planet).
constexpr double kFarM = 1e7;

}  // namespace

struct OpticalDepthGrid::Tile {
    int level;
    std::int64_t origin[3];  // vertex index of the tile's first corner on its level
    std::atomic<float> v[kV * kV * kV];
    // The aligned grid's cumulative depth C of the tile's own vertices (kTile per edge,
    // the shared faces held by the tile above them), allocated for an aligned grid only.
    std::unique_ptr<std::atomic<float>[]> c;
    Tile(int l, const std::int64_t o[3], bool aligned) : level(l), origin{o[0], o[1], o[2]} {
        constexpr float nan = std::numeric_limits<float>::quiet_NaN();
        for (auto& x : v) x.store(nan, std::memory_order_relaxed);
        if (aligned) {
            constexpr int n = kTile * kTile * kTile;
            c = std::make_unique<std::atomic<float>[]>(n);
            for (int i = 0; i < n; ++i) c[i].store(nan, std::memory_order_relaxed);
        }
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
      axis_{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}},
      map_(std::make_unique<Map>()) {
    if (!(h0_ > 0.0 && std::isfinite(h0_)))
        throw InvalidArgument("base_spacing_m", "must be a finite positive length");
    if (!(max_distance_m_ > 0.0)) throw InvalidArgument("max_distance_m", "must be positive");
    require_in_range("steps", steps_, 1, 1 << 16);
}

OpticalDepthGrid::OpticalDepthGrid(const CloudDensity& density, const glm::dvec3& direction,
                                   double base_spacing_m, double max_distance_m, int steps)
    : OpticalDepthGrid(density, Direction{}, base_spacing_m, max_distance_m, steps) {
    const double length = glm::length(direction);
    if (!(length > 0.0 && std::isfinite(length)))
        throw InvalidArgument("direction", "must be a finite, non-zero vector");
    const glm::dvec3 w = direction / length;
    direction_ = [w](const glm::dvec3&) { return w; };
    // Across w: the horizontal normal to it (x when w is vertical), then w x that.
    const glm::dvec3 c = glm::cross(w, glm::dvec3(0.0, 0.0, 1.0));
    axis_[0] = glm::length(c) > 1e-6 ? glm::normalize(c) : glm::dvec3(1.0, 0.0, 0.0);
    axis_[1] = glm::normalize(glm::cross(w, axis_[0]));
    axis_[2] = w;
    aligned_ = true;
}

OpticalDepthGrid::~OpticalDepthGrid() = default;

void OpticalDepthGrid::set_near_field(int levels, int steps) {
    require_in_range("levels", levels, 0, kMaxLevels - 1);
    require_in_range("steps", steps, 1, 64);
    if (!aligned_ && levels > 0)
        throw InvalidArgument("levels", "a near field needs a grid aligned with a constant direction");
    if (!map_->tiles.empty()) throw InvalidArgument("levels", "must be set before the first lookup");
    if (both_ways_ && levels > 0) throw InvalidArgument("levels", "a grid read both ways has no near field");
    near_levels_ = levels;
    near_steps_ = steps;
}

void OpticalDepthGrid::set_cross_spacing(double first, double second) {
    if (!aligned_) throw InvalidArgument("cross_spacing", "needs a grid aligned with a constant direction");
    if (!map_->tiles.empty()) throw InvalidArgument("cross_spacing", "must be set before the first lookup");
    for (const double f : {first, second})
        if (!(f >= 1.0 / 64.0 && f <= 64.0))
            throw InvalidArgument("cross_spacing", fmt::format("must be in [1/64, 64] cells, got {}", f));
    cross_[0] = first;
    cross_[1] = second;
}

void OpticalDepthGrid::set_chord_scaled(bool on) {
    if (!map_->tiles.empty()) throw InvalidArgument("chord", "must be set before the first lookup");
    chord_ = on;
}

void OpticalDepthGrid::set_both_ways(bool on) {
    if (!map_->tiles.empty()) throw InvalidArgument("both_ways", "must be set before the first lookup");
    if (on && (!aligned_ || near_levels_ > 0))
        throw InvalidArgument("both_ways",
                              "needs a grid aligned with a constant direction, without a near field");
    both_ways_ = on;
}

double OpticalDepthGrid::chord(const glm::dvec3& p, double reach, std::vector<MajorantSegment>& segs) const {
    segs.clear();
    const glm::dvec3 w = aligned_ ? axis_[2] : direction_(p);
    // Both ways: the line from p - reach w over twice the reach.
    const double span = both_ways_ ? 2.0 * reach : reach;
    density_.segments({both_ways_ ? p - reach * w : p, w}, span, segs);
    double length = 0.0;
    for (const auto& s : segs) length += std::max(0.0, std::min(s.t1, span) - std::max(s.t0, 0.0));
    return length;
}

glm::dvec3 OpticalDepthGrid::vertex_position(int level, std::int64_t i, std::int64_t j,
                                             std::int64_t k) const {
    const double h = spacing_m(level);
    if (!aligned_) return {double(i) * h, double(j) * h, double(k) * h};
    return h * (double(i) * cross_[0] * axis_[0] + double(j) * cross_[1] * axis_[1] + double(k) * axis_[2]);
}

int OpticalDepthGrid::level_for(double footprint_m) const {
    if (!(footprint_m > h0_)) return 0;
    return std::clamp(int(std::floor(std::log2(footprint_m / h0_))), 0, kMaxLevels - 1);
}

double OpticalDepthGrid::march(const glm::dvec3& p, std::vector<MajorantSegment>& segs) const {
    return march_at(p, max_distance_m_, segs);
}

double OpticalDepthGrid::march_at(const glm::dvec3& p, double reach,
                                  std::vector<MajorantSegment>& segs) const {
    const glm::dvec3 w = direction_(p);
    double tau = march_optical_depth(density_, {p, w}, reach, steps_, segs);
    if (both_ways_) tau += march_optical_depth(density_, {p, -w}, reach, steps_, segs);
    return tau;
}

OpticalDepthGrid::Tile* OpticalDepthGrid::find(std::uint64_t key) const {
    auto it = map_->tiles.find(key);
    return it == map_->tiles.end() ? nullptr : it->second.get();
}

namespace {

std::uint64_t tile_key(int level, const std::int64_t t[3]) {
    return (std::uint64_t(level) << (3 * kCoordBits)) |
           (std::uint64_t(t[0] + kCoordHalf) << (2 * kCoordBits)) |
           (std::uint64_t(t[1] + kCoordHalf) << kCoordBits) | std::uint64_t(t[2] + kCoordHalf);
}

// Floor division by kTile.
std::int64_t tile_of(std::int64_t v) {
    constexpr std::int64_t n = OpticalDepthGrid::kTile;
    return v >= 0 ? v / n : -((-v + n - 1) / n);
}

// Floor division by a positive n.
std::int64_t floor_div(std::int64_t v, std::int64_t n) { return v >= 0 ? v / n : -((-v + n - 1) / n); }

bool key_in_range(std::int64_t t) { return t > -kCoordHalf && t < kCoordHalf - 1; }

}  // namespace

OpticalDepthGrid::Tile* OpticalDepthGrid::tile_at(int level, const std::int64_t t[3], std::uint64_t* keys,
                                                  Tile** tiles, bool make) const {
    const std::uint64_t key = tile_key(level, t);
    const int slot = int((key ^ (key >> 20) ^ (key >> 40)) & (Cursor::kSlots - 1));
    if (key == keys[slot]) return tiles[slot];
    Tile* tile = find(key);
    if (!tile) {
        if (!make) return nullptr;
        const std::int64_t origin[3] = {t[0] * kTile, t[1] * kTile, t[2] * kTile};
        auto fresh = std::make_unique<Tile>(level, origin, aligned_);
        // Whoever inserts first wins; the loser's empty tile is dropped.
        tile = map_->tiles.emplace(key, std::move(fresh)).first->second.get();
    }
    keys[slot] = key;
    tiles[slot] = tile;
    return tile;
}

// C at vertex v if stored (NaN if not, or if its tile is absent), through the walk cache.
float OpticalDepthGrid::stored_cumulative(int level, const std::int64_t v[3], Cursor& cursor) const {
    const std::int64_t t[3] = {tile_of(v[0]), tile_of(v[1]), tile_of(v[2])};
    for (int a = 0; a < 3; ++a)
        if (!key_in_range(t[a])) return std::numeric_limits<float>::quiet_NaN();
    const Tile* tile = tile_at(level, t, cursor.walk_key, cursor.walk_tile, false);
    if (!tile) return std::numeric_limits<float>::quiet_NaN();
    const int idx =
        int(((v[2] - t[2] * kTile) * kTile + (v[1] - t[1] * kTile)) * kTile + (v[0] - t[0] * kTile));
    return tile->c[idx].load(std::memory_order_acquire);
}

// The cumulative depth C at vertex v (the header's recurrence): from its tile if stored,
// else walked along the line from v to the first stored vertex or the line's end, the new
// values stored from the far end back (release stores: each one published after every
// value beyond it).
double OpticalDepthGrid::cumulative(int level, const std::int64_t v[3], std::int64_t block,
                                    Cursor& cursor) const {
    const double h = spacing_m(level);
    const double delta = std::min(h, max_distance_m_ / steps_);  // the longest quadrature step
    const std::int64_t ti = tile_of(v[0]), tj = tile_of(v[1]);
    const int li = int(v[0] - ti * kTile), lj = int(v[1] - tj * kTile);
    auto& run = cursor.run;
    run.clear();
    double beyond = 0.0;  // C after the run's last vertex
    std::int64_t k = v[2];
    const std::int64_t block_end = (floor_div(k, block) + 1) * block;  // C = 0 there (its block's)
    Tile* tile = nullptr;
    std::int64_t kb = 0;  // the base vertex (along the line) of `tile`
    auto& segs = cursor.segs;
    glm::dvec3 base_x(0.0);
    while (k < block_end) {
        const std::int64_t tk = tile_of(k);
        if (!tile || tk * kTile != kb) {
            const std::int64_t t[3] = {ti, tj, tk};
            if (!key_in_range(tk)) break;  // past the key's range: nothing beyond counts
            tile = tile_at(level, t, cursor.walk_key, cursor.walk_tile, true);
            kb = tk * kTile;
            base_x = vertex_position(level, v[0], v[1], kb);
            segs.clear();
            density_.segments({base_x, axis_[2]}, kFarM, segs);
        }
        const int idx = int(((k - kb) * kTile + lj) * kTile + li);
        const float known = tile->c[idx].load(std::memory_order_acquire);
        if (!std::isnan(known)) {
            beyond = known;
            break;
        }
        // The cell [k, k + 1] along the line, from the tile's base vertex.
        const double ta = double(k - kb) * h, tb = ta + h;
        if (segs.empty() || ta >= segs.back().t1) {
            tile->c[idx].store(0.0f, std::memory_order_release);  // the line's end
            break;
        }
        run.push_back({tile, idx, midpoint_depth(density_, {base_x, axis_[2]}, segs, ta, tb, delta)});
        ++k;
    }
    // Back from the far end: C(k) = the cell's integral + C(k + 1), rounded to the stored float.
    for (auto it = run.rbegin(); it != run.rend(); ++it) {
        const float c = float(it->local + beyond);
        it->tile->c[it->index].store(c, std::memory_order_release);
        beyond = c;
    }
    return beyond;
}

// tau over max_distance_m at an aligned vertex (the header's blocks): C(v) less C at q
// cells further along its line, linear between the two vertices around that point, read in
// v's block or, past its end, as the next block's C at its first vertex less C there. An
// unset value after a known one in the same block is past the line's end: 0.
double OpticalDepthGrid::aligned_vertex(int level, const std::int64_t v[3], Cursor& cursor) const {
    const double h = spacing_m(level);
    // With the near field, the far part's vertices reach max_distance_m less one cell.
    const double q = (max_distance_m_ - (near_levels_ > 0 ? h : 0.0)) / h;
    if (!(q > 0.0)) return 0.0;
    if (!(q < 1e15)) return march(vertex_position(level, v[0], v[1], v[2]), cursor.segs);
    const std::int64_t block = std::int64_t(std::ceil(q)) + 1;
    const double c0 = cumulative(level, v, block, cursor);
    const std::int64_t kk = v[2] + std::int64_t(std::floor(q));
    const double f = q - std::floor(q);
    // C at vertex j of the line in the block ending at `end` (0 from there on).
    const auto at = [&](std::int64_t j, std::int64_t end) {
        if (j >= end) return 0.0;
        const std::int64_t w[3] = {v[0], v[1], j};
        const float c = stored_cumulative(level, w, cursor);
        return std::isnan(c) ? 0.0 : double(c);
    };
    const std::int64_t end = (floor_div(v[2], block) + 1) * block;
    if (kk < end) return std::max(0.0, c0 - (at(kk, end) + f * (at(kk + 1, end) - at(kk, end))));
    // The point lies in the next block (q < block: never beyond it). If v's line leaves the
    // density's segments before that block, it holds nothing.
    auto& segs = cursor.segs;
    segs.clear();
    density_.segments({vertex_position(level, v[0], v[1], v[2]), axis_[2]}, kFarM, segs);
    if (segs.empty() || segs.back().t1 <= double(end - v[2]) * h) return std::max(0.0, c0);
    const std::int64_t e[3] = {v[0], v[1], end};
    const double c_end = cumulative(level, e, block, cursor);
    const double far = at(kk, end + block) + f * (at(kk + 1, end + block) - at(kk, end + block));
    return std::max(0.0, c0 + c_end - far);
}

// The depth over positions [v - back, v + ahead] (cells) of vertex v's line: per block the
// span crosses, C at the span's start in it less C at its end (C linear between vertices, 0
// at the block's end, an unset value after a walked one past the line's end: 0).
double OpticalDepthGrid::aligned_span(int level, const std::int64_t v[3], double back, double ahead,
                                      Cursor& cursor) const {
    const double q = max_distance_m_ / spacing_m(level);
    const std::int64_t block = std::int64_t(std::ceil(q)) + 1;
    // C at position x of the line, in the block that ends at vertex `end`.
    const auto c_at = [&](double x, std::int64_t end) {
        const std::int64_t k = std::int64_t(std::floor(x));
        if (k >= end) return 0.0;
        const std::int64_t w[3] = {v[0], v[1], k}, w1[3] = {v[0], v[1], k + 1};
        const double c0 = cumulative(level, w, block, cursor);
        double c1 = 0.0;
        if (k + 1 < end) {
            const float c = stored_cumulative(level, w1, cursor);
            c1 = std::isnan(c) ? 0.0 : double(c);
        }
        return c0 + (x - double(k)) * (c1 - c0);
    };
    const double b = double(v[2]) + ahead;
    double x = double(v[2]) - back, total = 0.0;
    while (x < b) {
        const std::int64_t end = (floor_div(std::int64_t(std::floor(x)), block) + 1) * block;
        const double y = std::min(b, double(end));
        total += c_at(x, end) - c_at(y, end);
        x = y;
    }
    return std::max(0.0, total);
}

double OpticalDepthGrid::tau(const glm::dvec3& p, int level, Cursor& cursor, bool near_field) const {
    if (!aligned_ || near_levels_ <= 0 || !near_field) return grid_tau(p, level, cursor);
    const int far = std::min(level + near_levels_, kMaxLevels - 1);
    const double d = std::min(spacing_m(far), max_distance_m_);
    // The midpoint rule over the parts of [0, d] inside the majorant segments, steps no
    // longer than d / near_steps_ (exact on a constant density, as a vertex's cells).
    auto& segs = cursor.segs;
    segs.clear();
    density_.segments({p, axis_[2]}, d, segs);
    const double near = midpoint_depth(density_, {p, axis_[2]}, segs, 0.0, d, d / near_steps_);
    if (!(d < max_distance_m_)) return near;
    return near + grid_tau(p + d * axis_[2], far, cursor);
}

double OpticalDepthGrid::grid_tau(const glm::dvec3& p, int level, Cursor& cursor) const {
    const double h = spacing_m(level);
    double w[3];
    std::int64_t base[3], tcoord[3];
    for (int a = 0; a < 3; ++a) {
        const double u = aligned_ ? glm::dot(axis_[a], p) / (h * cross_[a]) : p[a] / h;
        const double b = std::floor(u);
        w[a] = u - b;
        base[a] = std::int64_t(b);
        // Tile of the cell (floor division), within the key's range; else march directly.
        tcoord[a] = tile_of(base[a]);
        if (!(std::abs(b) < 1e15) || tcoord[a] <= -kCoordHalf || tcoord[a] >= kCoordHalf - 1)
            return march(p, cursor.segs);
    }
    // The vertices' reach: max_distance_m, less one cell where the near field's first cell
    // is marched by the lookup (aligned_vertex).
    const double reach = max_distance_m_ - (aligned_ && near_levels_ > 0 ? h : 0.0);
    const double length = chord_ ? chord(p, reach, cursor.segs) : 0.0;
    if (chord_ && !(length > 0.0)) return 0.0;
    Tile& t = *tile_at(level, tcoord, cursor.key, cursor.tile, true);
    const int li = int(base[0] - t.origin[0]), lj = int(base[1] - t.origin[1]),
              lk = int(base[2] - t.origin[2]);
    double corner[8];
    for (int c = 0; c < 8; ++c) {
        const int i = li + (c & 1), j = lj + ((c >> 1) & 1), k = lk + ((c >> 2) & 1);
        std::atomic<float>& vertex = t.v[(k * kV + j) * kV + i];
        float v = vertex.load(std::memory_order_relaxed);
        if (std::isnan(v)) {
            const std::int64_t vi[3] = {t.origin[0] + i, t.origin[1] + j, t.origin[2] + k};
            const glm::dvec3 x = vertex_position(level, vi[0], vi[1], vi[2]);
            const double q = max_distance_m_ / h;
            const double tau = both_ways_ ? aligned_span(level, vi, q, q, cursor)
                               : aligned_ ? aligned_vertex(level, vi, cursor)
                                          : march(x, cursor.segs);
            if (chord_) {
                const double l = chord(x, reach, cursor.segs);
                v = l > 0.0 ? float(tau / l) : -1.0f;  // -1: no segment on the vertex's line
            } else {
                v = float(tau);
            }
            vertex.store(v, std::memory_order_relaxed);
        }
        corner[c] = v;
    }
    if (chord_) {
        double sum = 0.0, weight = 0.0;
        for (int c = 0; c < 8; ++c) {
            if (corner[c] < 0.0) continue;
            const double wc =
                (c & 1 ? w[0] : 1.0 - w[0]) * (c & 2 ? w[1] : 1.0 - w[1]) * (c & 4 ? w[2] : 1.0 - w[2]);
            sum += wc * corner[c];
            weight += wc;
        }
        if (!(weight > 0.0)) return march_at(p, reach, cursor.segs);
        return length * sum / weight;
    }
    const auto lerp = [](double a, double b, double s) { return a + s * (b - a); };
    const double x00 = lerp(corner[0], corner[1], w[0]), x10 = lerp(corner[2], corner[3], w[0]);
    const double x01 = lerp(corner[4], corner[5], w[0]), x11 = lerp(corner[6], corner[7], w[0]);
    return lerp(lerp(x00, x10, w[1]), lerp(x01, x11, w[1]), w[2]);
}

}  // namespace welkin
