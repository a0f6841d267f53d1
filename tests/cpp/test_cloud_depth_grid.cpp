// SPDX-License-Identifier: Apache-2.0
// The lazily filled optical-depth grid (clouds/depth_grid.hpp) and the march through it.
#include <cmath>
#include <cstdio>
#include <string>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "welkin/base/math.hpp"
#include "welkin/base/rng.hpp"
#include "welkin/clouds/depth_grid.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/vdb.hpp"

using namespace welkin;

namespace {

// The exact optical depth from p along unit s out of the box [lo, hi] of sigma, p inside.
double box_depth(const glm::dvec3& p, const glm::dvec3& s, const glm::dvec3& lo, const glm::dvec3& hi,
                 double sigma) {
    double t = 1e30;
    for (int a = 0; a < 3; ++a) {
        if (s[a] > 0) t = std::min(t, (hi[a] - p[a]) / s[a]);
        if (s[a] < 0) t = std::min(t, (lo[a] - p[a]) / s[a]);
    }
    return sigma * t;
}

// The shadow rays per sample the grids are measured against: fine enough that their own
// quadrature is not the difference (the grids aligned with the sun integrate each cell,
// a lookup per cell at the finest levels, where a march of the default 8 steps is off by
// tens of per cent per ray on a cumulus: AlignedVerticesMatchAFineMarch).
constexpr int kFineLightSteps = 128;

double grid_h(const OpticalDepthGrid& grid, int level) { return grid.spacing_m(level); }

// A point of the box [lo, hi], every odd i's within 40 m of its bottom or top face (where
// the depth's kink is; outside the box half the time).
glm::dvec3 point_near_faces(PathRng& rng, const glm::dvec3& lo, const glm::dvec3& hi, int i) {
    glm::dvec3 p = lo + glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * (hi - lo);
    if (i % 2) p.z = (rng.uniform() < 0.5 ? lo.z : hi.z) + (rng.uniform() - 0.5) * 2.0 * 40.0;
    return p;
}

// The grids' march against a reference march over a set of views, on the green channel:
// the relative difference of the sums, the mean |difference| over the reference's sum, and
// whether every view of the grids' march is finite.
struct Agreement {
    double mean = 0.0, mean_abs = 0.0, ref_sum = 0.0;
    bool finite = true;
};
Agreement green_agreement(const CloudResult& grid, const CloudResult& ref) {
    double sg = 0, sr = 0, sa = 0;
    Agreement a;
    for (std::size_t r = 0; r < grid.transmittance.size(); ++r) {
        const double g = grid.radiance[r * 3 + 1], f = ref.radiance[r * 3 + 1];
        a.finite = a.finite && std::isfinite(g);
        sg += g, sr += f, sa += std::abs(g - f);
    }
    a.mean = sg / sr - 1.0, a.mean_abs = sa / sr, a.ref_sum = sr;
    return a;
}

}  // namespace

// In a homogeneous box tau(p) = sigma * (distance to the exit along s): piecewise linear,
// so trilinear interpolation is exact inside the linear pieces and off by at most the
// change of tau over a cell diagonal where a cell straddles a kink or a face. Bound:
// sigma h sqrt(3) at every point (h the cell of the level read), and the vertices hold
// exactly the march (which is exact on a constant density).
TEST(CloudDepthGrid, HomogeneousBoxWithinOneCell) {
    const glm::dvec3 lo(-300.0, -200.0, 1000.0), hi(500.0, 400.0, 1600.0);
    const double sigma = 0.01;
    const test::HomogeneousBox box(lo, hi, sigma);
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    const OpticalDepthGrid grid(
        box, [s](const glm::dvec3&) { return s; }, 10.0, 1e5, 4);
    OpticalDepthGrid::Cursor cursor;
    PathRng rng(7, 0, 0);
    for (int level : {0, 2}) {
        const double h = grid.spacing_m(level);
        double worst = 0.0, mean = 0.0;
        const int n = 2000;
        for (int i = 0; i < n; ++i) {
            const glm::dvec3 p = lo + glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * (hi - lo);
            const double e = std::abs(grid.tau(p, level, cursor) - box_depth(p, s, lo, hi, sigma));
            worst = std::max(worst, e);
            mean += e / n;
        }
        std::printf("level %d (h %.0f m): max |tau error| %.4f, mean %.5f, bound %.4f\n", level, h, worst,
                    mean, sigma * h * std::sqrt(3.0));
        EXPECT_LE(worst, sigma * h * std::sqrt(3.0));
    }
    // At a vertex the grid holds the march itself.
    const glm::dvec3 v(100.0, 50.0, 1200.0);  // a multiple of h_0 = 10 m on every axis
    std::vector<MajorantSegment> segs;
    EXPECT_NEAR(grid.tau(v, 0, cursor), grid.march(v, segs), 1e-6 * grid.march(v, segs));
    EXPECT_NEAR(grid.march(v, segs), box_depth(v, s, lo, hi, sigma), 1e-9);
    EXPECT_EQ(grid.level_for(5.0), 0);
    EXPECT_EQ(grid.level_for(45.0), 2);
    EXPECT_THROW(OpticalDepthGrid(
                     box, [s](const glm::dvec3&) { return s; }, 0.0, 1e5, 4),
                 InvalidArgument);
}

// The march through the grid gives the same bits for any thread count (a vertex's value
// does not depend on who computes it), and stays close to a shadow ray and a zenith ray per
// sample, both marched finely: on a procedural cumulus seen from below, the mean radiance
// within 2 % and the mean absolute difference per view within 5 % (measured: +0.3 % and
// 2.0 %; bench/clouds shows the same on a whole sky's rays).
TEST(CloudDepthGrid, MarchIsThreadIndependentAndMatchesPerSampleShadows) {
    CloudLayerParams p;
    p.coverage = 0.7;
    p.density_per_m = 0.02;
    const ProceduralClouds layer(p);
    const double e = 35.0 * kDegree;
    const ConstantIllumination light({std::cos(e), 0.0, std::sin(e)}, {1.0f, 1.0f, 1.0f},
                                     {0.04f, 0.04f, 0.04f});
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < 24; ++j)
        for (int i = 0; i < 24; ++i)
            dirs.push_back(glm::normalize(glm::dvec3((i - 11.5) / 12.0, (j - 11.5) / 12.0, 1.0)));
    CloudLightingOptions o;
    o.scattering.albedo = 0.95;  // the zenith grid too
    CloudResult one, many;
    {
        const tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = render_clouds(layer, light, {0, 0, 0}, dirs, o);
    }
    many = render_clouds(layer, light, {0, 0, 0}, dirs, o);
    EXPECT_EQ(one.radiance, many.radiance);
    EXPECT_EQ(one.transmittance, many.transmittance);
    CloudLightingOptions per_sample = o;
    per_sample.shadow_grid = false;
    per_sample.light_steps = kFineLightSteps;
    per_sample.ambient_steps = kFineLightSteps;
    const CloudResult ref = render_clouds(layer, light, {0, 0, 0}, dirs, per_sample);
    const Agreement d = green_agreement(many, ref);
    ASSERT_TRUE(d.finite);
    std::printf("grid vs per-sample shadow rays: mean %+.2f %%, mean |diff| %.2f %%\n", 100 * d.mean,
                100 * d.mean_abs);
    EXPECT_LT(std::abs(d.mean), 0.02);
    EXPECT_LT(d.mean_abs, 0.05);
}

// The grids read no finer than the rays' footprint (ray_spread_rad, lighting.hpp): a mid
// and a high layer seen from the ground through a fan of rays as an image's pixels are
// (0.02 rad apart), against a shadow ray per sample (which no level choice touches): the
// mean radiance within 2 % and the mean absolute difference per view within 5 %, as for
// the grid at the view step's levels above; the same bits for any thread count. The
// footprint's levels are what keep a deck kilometres up as fast as a low one (the vertices
// of cells finer than the rays' spacing are each read by one ray; bench/clouds --types-only).
TEST(CloudDepthGrid, FootprintLevelsMatchPerSampleShadows) {
    const double e = 35.0 * kDegree;
    const ConstantIllumination light({std::cos(e), 0.0, std::sin(e)}, {1.0f, 1.0f, 1.0f},
                                     {0.04f, 0.04f, 0.04f});
    const double spread = 0.02;
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < 24; ++j)
        for (int i = 0; i < 24; ++i)
            dirs.push_back(glm::normalize(
                glm::dvec3(std::tan((i - 11.5) * spread), 0.3 + std::tan((j - 11.5) * spread), 1.0)));
    for (const CloudType type : {CloudType::altocumulus, CloudType::cirrus}) {
        CloudLayerParams p = CloudLayerParams::preset(type);
        p.coverage = 0.6;
        const ProceduralClouds layer(p);
        CloudLightingOptions o;
        o.ray_spread_rad = spread;
        CloudResult one, many;
        {
            const tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
            one = render_clouds(layer, light, {0, 0, 0}, dirs, o);
        }
        many = render_clouds(layer, light, {0, 0, 0}, dirs, o);
        EXPECT_EQ(one.radiance, many.radiance);
        EXPECT_EQ(one.transmittance, many.transmittance);
        CloudLightingOptions per_sample = o;
        per_sample.shadow_grid = false;
        per_sample.light_steps = kFineLightSteps;
        const CloudResult ref = render_clouds(layer, light, {0, 0, 0}, dirs, per_sample);
        const Agreement d = green_agreement(many, ref);
        ASSERT_TRUE(d.finite);
        double cloudy = 0;
        for (std::size_t r = 0; r < dirs.size(); ++r) {
            EXPECT_EQ(many.transmittance[r], ref.transmittance[r]);  // the view march is the same
            cloudy += ref.transmittance[r] < 0.9f;
        }
        std::printf(
            "%s, footprint levels vs per-sample shadow rays: mean %+.2f %%, mean |diff| %.2f %% "
            "(%g of %zu views cloudy)\n",
            std::string(cloud_type_name(type)).c_str(), 100 * d.mean, 100 * d.mean_abs, cloudy, dirs.size());
        EXPECT_GT(cloudy, 50.0);
        EXPECT_LT(std::abs(d.mean), 0.02);
        EXPECT_LT(d.mean_abs, 0.05);
    }
    CloudLightingOptions bad;
    bad.ray_spread_rad = -0.1;
    EXPECT_THROW(bad.validate(), InvalidArgument);
    bad.ray_spread_rad = 0.0;
    bad.ray_width_m = std::nan("");
    EXPECT_THROW(bad.validate(), InvalidArgument);
}

// The grid aligned with a constant direction (depth_grid.hpp, "Aligned"): its vertices on
// one line share a walk. In a homogeneous box tau is exact at every vertex (the cell
// integrals are clipped to the box, and the difference C(k) - C(x_k + D w) is exact on a
// constant density) and within a cell diagonal's change everywhere, as for the march per
// vertex; the cut at max_distance_m holds (exactly where the box's far side is not within
// a cell of the cut point).
TEST(CloudDepthGrid, AlignedGridExactInAHomogeneousBox) {
    const glm::dvec3 lo(-300.0, -200.0, 1000.0), hi(500.0, 400.0, 1600.0);
    const double sigma = 0.01;
    const test::HomogeneousBox box(lo, hi, sigma);
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    for (const double reach : {1e5, 250.0}) {
        const OpticalDepthGrid grid(box, s, 10.0, reach, 4);
        ASSERT_TRUE(grid.aligned());
        OpticalDepthGrid::Cursor cursor;
        PathRng rng(7, 0, 0);
        const auto exact = [&](const glm::dvec3& p) {
            return std::min(box_depth(p, s, lo, hi, sigma), sigma * reach);
        };
        for (int level : {0, 2}) {
            const double h = grid.spacing_m(level);
            double worst = 0.0, worst_vertex = 0.0;
            for (int i = 0; i < 2000; ++i) {
                const glm::dvec3 p = lo + glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * (hi - lo);
                worst = std::max(worst, std::abs(grid.tau(p, level, cursor) - exact(p)));
                // The vertex below p on each axis of the aligned frame.
                const glm::dvec3 u(glm::dot(p, grid.vertex_position(level, 1, 0, 0)) / (h * h),
                                   glm::dot(p, grid.vertex_position(level, 0, 1, 0)) / (h * h),
                                   glm::dot(p, grid.vertex_position(level, 0, 0, 1)) / (h * h));
                const glm::dvec3 v =
                    grid.vertex_position(level, std::int64_t(std::floor(u.x)), std::int64_t(std::floor(u.y)),
                                         std::int64_t(std::floor(u.z)));
                // C is linear along the line between the two vertices around x + D w
                // unless the box's far side lies between them (then within a cell's change).
                const double exit = box_depth(v, s, lo, hi, sigma) / sigma;
                if (box.sigma_t(v) > 0.0 && std::abs(exit - reach) > h)
                    worst_vertex = std::max(worst_vertex, std::abs(grid.tau(v, level, cursor) - exact(v)));
            }
            std::printf(
                "aligned, reach %g m, level %d: max |tau error| %.5f (bound %.4f), at vertices %.2e\n", reach,
                level, worst, sigma * h * std::sqrt(3.0), worst_vertex);
            EXPECT_LE(worst, sigma * h * std::sqrt(3.0));
            EXPECT_LE(worst_vertex, 1e-4);
        }
    }
    // The near field: the first cell of the level above marched per lookup, the rest read
    // there; within that level's cell diagonal plus the near march's own error (a face
    // crossed between its two midpoints: half a near step of depth).
    OpticalDepthGrid near(box, s, 10.0, 1e5, 4);
    near.set_near_field(1, 2);
    OpticalDepthGrid::Cursor cursor;
    PathRng rng(9, 0, 0);
    double worst = 0.0;
    for (int i = 0; i < 2000; ++i) {
        const glm::dvec3 p = lo + glm::dvec3(rng.uniform(), rng.uniform(), rng.uniform()) * (hi - lo);
        worst = std::max(worst, std::abs(near.tau(p, 0, cursor) - box_depth(p, s, lo, hi, sigma)));
    }
    std::printf("aligned with the near field, level 0: max |tau error| %.5f\n", worst);
    EXPECT_LE(worst, sigma * 20.0 * std::sqrt(3.0) + sigma * 10.0);
    EXPECT_THROW(near.set_near_field(2, 2), InvalidArgument);  // after the first lookup
    EXPECT_THROW(OpticalDepthGrid(box, glm::dvec3(0.0), 10.0, 1e5, 4), InvalidArgument);
}

// The chord (depth_grid.hpp, "Chord"): a vertex holds the mean extinction along its line,
// and a lookup multiplies the interpolated mean by its own chord through the majorant
// segments. In a homogeneous box the mean is sigma on every line that meets the box, so
// the lookup is exact at every point, including the cells a face cuts, where the depth's
// kink puts the plain interpolation off by up to sigma h sqrt(3) (the test above): on a
// grid of world axes marching each vertex, on one turned to s, and with the near field.
TEST(CloudDepthGrid, ChordScaledGridExactInAHomogeneousBox) {
    const glm::dvec3 lo(-300.0, -200.0, 1000.0), hi(500.0, 400.0, 1600.0);
    const double sigma = 0.01;
    const test::HomogeneousBox box(lo, hi, sigma);
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    OpticalDepthGrid world(
        box, [s](const glm::dvec3&) { return s; }, 10.0, 1e5, 4);
    OpticalDepthGrid aligned(box, s, 10.0, 1e5, 4), near(box, s, 10.0, 1e5, 4), plain(box, s, 10.0, 1e5, 4);
    near.set_near_field(1, 2);
    for (OpticalDepthGrid* g : {&world, &aligned, &near}) g->set_chord_scaled(true);
    const char* names[] = {"world axes", "aligned", "aligned, near field"};
    OpticalDepthGrid::Cursor cursors[4];  // one per grid: a cursor caches its grid's tiles
    std::vector<MajorantSegment> segs;
    for (int level : {0, 2}) {
        PathRng rng(11, std::uint64_t(level), 0);
        double worst[3] = {}, worst_plain = 0.0;
        for (int i = 0; i < 4000; ++i) {
            const glm::dvec3 p = point_near_faces(rng, lo, hi, i);
            // The march is exact on a constant density (its steps clipped to the box).
            const double exact = march_optical_depth(box, {p, s}, 1e5, 4, segs);
            const OpticalDepthGrid* grids[] = {&world, &aligned, &near};
            for (int g = 0; g < 3; ++g)
                worst[g] = std::max(worst[g], std::abs(grids[g]->tau(p, level, cursors[g]) - exact));
            worst_plain = std::max(worst_plain, std::abs(plain.tau(p, level, cursors[3]) - exact));
        }
        for (int g = 0; g < 3; ++g) {
            std::printf("chord-scaled, %s, level %d: max |tau error| %.2e (plain interpolation %.4f)\n",
                        names[g], level, worst[g], worst_plain);
            EXPECT_LE(worst[g], 1e-5 * sigma * 2000.0);  // the float vertex and rounding: 1e-5 of the deepest
        }
        EXPECT_GT(worst_plain, 0.1 * sigma * grid_h(aligned, level));  // what the chord removes
    }
    EXPECT_THROW(world.set_chord_scaled(false), InvalidArgument);  // after the first lookup
}

// Both ways (depth_grid.hpp, "Both ways"): the depth over the whole chord through p, from
// p - D s to p + D s, read from one grid's walks. In a homogeneous box, with the chord, exact
// at every point (the span's ends linear between vertices, exact on a constant density);
// with a short reach the span's cut at both ends is exact where no face lies within a cell
// of either end; without the chord, within the plain interpolation's cell diagonal.
TEST(CloudDepthGrid, BothWaysIsTheChordThroughThePoint) {
    const glm::dvec3 lo(-300.0, -200.0, 1000.0), hi(500.0, 400.0, 1600.0);
    const double sigma = 0.01;
    const test::HomogeneousBox box(lo, hi, sigma);
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    std::vector<MajorantSegment> segs;
    for (const double reach : {2000.0, 300.0}) {  // past the box's diagonal (1150 m), and within it
        OpticalDepthGrid chord(box, s, 10.0, reach, 4), plain(box, s, 10.0, reach, 4);
        chord.set_chord_scaled(true);
        chord.set_both_ways(true);
        plain.set_both_ways(true);
        OpticalDepthGrid::Cursor c1, c2;
        PathRng rng(13, 0, 0);
        double worst_chord = 0.0, worst_plain = 0.0;
        for (int i = 0; i < 4000; ++i) {
            const glm::dvec3 p = point_near_faces(rng, lo, hi, i);
            const double exact = march_optical_depth(box, {p, s}, reach, 4, segs) +
                                 march_optical_depth(box, {p, -s}, reach, 4, segs);
            // Where a face lies within a cell of a span's end, the linear C there is not exact.
            const double ahead = box_depth(p, s, lo, hi, 1.0), behind = box_depth(p, -s, lo, hi, 1.0);
            const bool cut_near_face =
                box.sigma_t(p) > 0.0 && (std::abs(ahead - reach) < 2.0 * 10.0 * std::sqrt(3.0) ||
                                         std::abs(behind - reach) < 2.0 * 10.0 * std::sqrt(3.0));
            if (!cut_near_face) worst_chord = std::max(worst_chord, std::abs(chord.tau(p, 0, c1) - exact));
            worst_plain = std::max(worst_plain, std::abs(plain.tau(p, 0, c2) - exact));
        }
        std::printf("both ways, reach %g m: chord-scaled max |tau error| %.2e, plain %.4f (bound %.4f)\n",
                    reach, worst_chord, worst_plain, 2.0 * sigma * 10.0 * std::sqrt(3.0));
        EXPECT_LE(worst_chord, 1e-5 * sigma * 2000.0);
        EXPECT_LE(worst_plain, 2.0 * sigma * 10.0 * std::sqrt(3.0));  // a kink at each end
    }
    OpticalDepthGrid world(
        box, [s](const glm::dvec3&) { return s; }, 10.0, 1e5, 4);
    EXPECT_THROW(world.set_both_ways(true), InvalidArgument);  // not aligned
    OpticalDepthGrid near(box, s, 10.0, 1e5, 4), both(box, s, 10.0, 1e5, 4);
    near.set_near_field(1, 2);
    EXPECT_THROW(near.set_both_ways(true), InvalidArgument);
    both.set_both_ways(true);
    EXPECT_THROW(both.set_near_field(1, 2), InvalidArgument);
}

// Cross spacing (depth_grid.hpp): the lines spaced apart by their own factors across the
// direction. The chord-scaled grid stays exact in a homogeneous box (its mean extinction is
// the box's on every line that meets it), the vertices lie at the scaled spacing, and the
// setter refuses what it cannot honour.
TEST(CloudDepthGrid, CrossSpacingKeepsTheChordExact) {
    const glm::dvec3 lo(-300.0, -200.0, 1000.0), hi(500.0, 400.0, 1600.0);
    const double sigma = 0.01;
    const test::HomogeneousBox box(lo, hi, sigma);
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, -0.8, 0.0));  // horizontal, as the sides'
    std::vector<MajorantSegment> segs;
    OpticalDepthGrid grid(box, s, 10.0, 2000.0, 4);
    grid.set_chord_scaled(true);
    grid.set_both_ways(true);
    grid.set_cross_spacing(2.0, 0.25);
    const glm::dvec3 a = grid.vertex_position(1, 1, 0, 0), b = grid.vertex_position(1, 0, 1, 0),
                     c = grid.vertex_position(1, 0, 0, 1);
    EXPECT_NEAR(glm::length(a), 40.0, 1e-9);  // 2 cells of 20 m across, horizontal
    EXPECT_NEAR(a.z, 0.0, 1e-9);
    EXPECT_NEAR(glm::length(b), 5.0, 1e-9);  // a quarter cell in the vertical
    EXPECT_NEAR(std::abs(b.z), 5.0, 1e-9);
    EXPECT_NEAR(glm::length(c), 20.0, 1e-9);  // a cell along the line
    OpticalDepthGrid::Cursor cursor;
    PathRng rng(17, 0, 0);
    double worst = 0.0;
    for (int i = 0; i < 4000; ++i) {
        const glm::dvec3 p = point_near_faces(rng, lo, hi, i);
        const double exact = march_optical_depth(box, {p, s}, 2000.0, 4, segs) +
                             march_optical_depth(box, {p, -s}, 2000.0, 4, segs);
        worst = std::max(worst, std::abs(grid.tau(p, 0, cursor) - exact));
    }
    EXPECT_LE(worst, 1e-5 * sigma * 2000.0);
    EXPECT_THROW(grid.set_cross_spacing(1.0, 1.0), InvalidArgument);  // after the first lookup
    OpticalDepthGrid fresh(box, s, 10.0, 2000.0, 4);
    for (const double bad : {0.0, 1.0 / 128.0, 128.0, std::nan("")})
        EXPECT_THROW(fresh.set_cross_spacing(1.0, bad), InvalidArgument);
    OpticalDepthGrid world(
        box, [s](const glm::dvec3&) { return s; }, 10.0, 1e5, 4);
    EXPECT_THROW(world.set_cross_spacing(1.0, 0.5), InvalidArgument);  // not aligned
}

// The sides' chord (lighting.cpp, levels_for) read from its grid against the same march
// with every depth marched per sample (128 steps), on an overcast stratus deck seen from
// the ground towards its base, 5-25 degrees up, the sun 30 degrees up and 60 degrees to the
// side (the Cycles chart's side view): just above the flat base the chord runs through the
// base's density ramp, and a horizontal line's depth changes over metres up the deck. The
// mean within 3 % and the mean |difference| per view within 4 % (measured: -0.3 % and
// 0.5 %; on cubic cells one level coarser than the sun's, +7.5 % and 7.5 %).
TEST(CloudDepthGrid, SidesChordMatchesPerSampleAtADeckBase) {
    const double e = 30.0 * kDegree, az = 60.0 * kDegree;
    const ConstantIllumination light({std::cos(e) * std::sin(az), std::cos(e) * std::cos(az), std::sin(e)},
                                     {1.0f, 1.0f, 1.0f}, {0.0f, 0.0f, 0.0f});
    const double spread = 0.005;
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < 20; ++j)
        for (int i = 0; i < 24; ++i) {
            const double el = (5.0 + j) * kDegree, a = (i - 11.5) * kDegree;
            dirs.push_back({std::cos(el) * std::sin(a), std::cos(el) * std::cos(a), std::sin(el)});
        }
    CloudLayerParams p = CloudLayerParams::preset(CloudType::stratus);
    p.coverage = 1.0;
    const ProceduralClouds layer(p);
    CloudLightingOptions o;
    o.ray_spread_rad = spread;
    const CloudResult grid = render_clouds(layer, light, {0, 0, 0}, dirs, o);
    CloudLightingOptions per_sample = o;
    per_sample.shadow_grid = false;
    per_sample.light_steps = kFineLightSteps;
    const CloudResult ref = render_clouds(layer, light, {0, 0, 0}, dirs, per_sample);
    const Agreement d = green_agreement(grid, ref);
    ASSERT_TRUE(d.finite);
    std::printf("stratus base, grids vs per-sample depths: mean %+.2f %%, mean |diff| %.2f %%\n",
                100 * d.mean, 100 * d.mean_abs);
    EXPECT_GT(d.ref_sum, 0.0);
    EXPECT_LT(std::abs(d.mean), 0.03);
    EXPECT_LT(d.mean_abs, 0.04);
}

// On a procedural layer the aligned grid's vertices hold the optical depth of a fine march
// (4096 steps over max_distance_m) to within the quadrature of one lookup per cell: per
// type, 400 vertices in the layer, the mean error (bias) within 1 % of the mean depth and
// the mean |error| within 5 % and below that of a march of light_steps = 8 steps per vertex
// (what a vertex held before the walk; measured: 0.9, 3.4, 1.4 % against 31, 4.3, 26 % for
// cumulus, stratus, cirrus).
TEST(CloudDepthGrid, AlignedVerticesMatchAFineMarch) {
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    for (const CloudType type : {CloudType::cumulus, CloudType::stratus, CloudType::cirrus}) {
        const CloudLayerParams lp = CloudLayerParams::preset(type);
        const ProceduralClouds layer(lp);
        const double h0 = 2.0 * layer.feature_size_m(), reach = 4000.0;
        const OpticalDepthGrid grid(layer, s, h0, reach, 8);
        OpticalDepthGrid::Cursor cursor;
        std::vector<MajorantSegment> segs;
        PathRng rng(11, 0, 0);
        double sum = 0.0, bias = 0.0, abs_err = 0.0, abs_err8 = 0.0;
        int n = 0;
        while (n < 400) {
            const glm::dvec3 p(
                20000.0 * (rng.uniform() - 0.5), 20000.0 * (rng.uniform() - 0.5),
                lp.bottom_altitude_m + rng.uniform() * (lp.top_altitude_m - lp.bottom_altitude_m));
            // The grid's vertex nearest p (level 0).
            const glm::dvec3 u(glm::dot(p, grid.vertex_position(0, 1, 0, 0)) / (h0 * h0),
                               glm::dot(p, grid.vertex_position(0, 0, 1, 0)) / (h0 * h0),
                               glm::dot(p, grid.vertex_position(0, 0, 0, 1)) / (h0 * h0));
            const glm::dvec3 v =
                grid.vertex_position(0, std::llround(u.x), std::llround(u.y), std::llround(u.z));
            const double fine = march_optical_depth(layer, {v, s}, reach, 4096, segs);
            if (!(fine > 0.05)) continue;
            const double g = grid.tau(v, 0, cursor),
                         coarse = march_optical_depth(layer, {v, s}, reach, 8, segs);
            sum += fine, bias += g - fine, abs_err += std::abs(g - fine), abs_err8 += std::abs(coarse - fine);
            ++n;
        }
        std::printf(
            "%s: mean depth %.3f, aligned grid bias %+.2f %%, mean |error| %.2f %% (8-step march %.2f %%)\n",
            std::string(cloud_type_name(type)).c_str(), sum / n, 100 * bias / sum, 100 * abs_err / sum,
            100 * abs_err8 / sum);
        EXPECT_LT(std::abs(bias) / sum, 0.01);
        EXPECT_LT(abs_err / sum, 0.05);
        EXPECT_LT(abs_err, abs_err8);
    }
}

// The lit top of a deck seen against a low sun (the Cycles chart's backlit view of the
// stratus patch, docs/validation.md "The sun grid's lines under a low sun"): a VDB deck
// of 40 m voxels, its density ramping down over its top three voxels, seen from the ground
// 5 km from its near edge across that edge, the sun 16 degrees up behind it and 3 degrees
// to the side; the rays a fan 0.004 rad apart, as an image's pixels are. Just below the
// top a sample's sun line climbs out through the ramp, and its depth falls from the deck's
// to 0 within a few tens of metres up; across the sun grid's lines one cell apart (80 m,
// tilted 16 degrees from the vertical) that profile was interpolated deep, and the lit
// rim came out dark against the per-sample shadow rays (mean -16.2 %, mean |difference|
// per view 16.8 %). On lines tan(16 deg) of a cell apart (lighting.cpp,
// sun_cross_spacing; measured -2.3 % and 2.9 %): the mean within 3 % and the mean
// |difference| per view within 5 %.
TEST(CloudDepthGrid, SunGridMatchesPerSampleAtABacklitDeckTop) {
    test::TempDir dir;
    const std::string path = dir.file("deck.vdb");
    // Voxels k = -5..5 (z = 800..1200 m after the move below), the top three ramping down.
    test::write_vdb(path, {test::make_float_grid("density", 40.0, 40, [](int i, int j, int k) {
                        if (std::abs(i) > 37 || std::abs(j) > 37 || k < -5 || k > 5) return 0.0f;
                        return k <= 2 ? 1.0f : float(6 - k) / 4.0f;
                    })});
    VdbCloudOptions vo;
    vo.matrix_world = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 0.0, 1000.0));
    vo.density_scale = 0.04;
    vo.placement = VdbCloudOptions::VoxelPlacement::OpenVdb;
    const VdbClouds deck(path, vo);
    const glm::dvec3 camera(-6500.0, 0.0, 1.5);
    const double e = 16.0 * kDegree, az = 3.0 * kDegree;
    const ConstantIllumination light({std::cos(e) * std::cos(az), std::cos(e) * std::sin(az), std::sin(e)},
                                     {1.0f, 1.0f, 1.0f}, {0.05f, 0.05f, 0.05f}, {0.02f, 0.02f, 0.02f});
    // The near top edge (x = -1500 m, z = 1200 m) is 13.5 degrees up from the camera.
    const double edge = std::atan2(1200.0 - camera.z, -camera.x - 1500.0);
    const double spread = 0.004;
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 12; ++i) {
            const double el = edge + (j - 9.5) * spread, a = (i - 5.5) * spread;
            dirs.push_back({std::cos(el) * std::cos(a), std::cos(el) * std::sin(a), std::sin(el)});
        }
    CloudLightingOptions o;
    o.ray_spread_rad = spread;
    const CloudResult grid = render_clouds(deck, light, camera, dirs, o);
    CloudLightingOptions per_sample = o;
    per_sample.shadow_grid = false;
    per_sample.light_steps = kFineLightSteps;
    const CloudResult ref = render_clouds(deck, light, camera, dirs, per_sample);
    const Agreement d = green_agreement(grid, ref);
    ASSERT_TRUE(d.finite);
    int rim = 0;  // views through the ramp: neither clear nor opaque
    for (std::size_t r = 0; r < dirs.size(); ++r)
        rim += ref.transmittance[r] > 0.02f && ref.transmittance[r] < 0.98f;
    std::printf(
        "backlit deck top, sun grid vs per-sample depths: mean %+.2f %%, mean |diff| %.2f %% (%d rim "
        "views)\n",
        100 * d.mean, 100 * d.mean_abs, rim);
    EXPECT_GE(rim, 12);
    EXPECT_LT(std::abs(d.mean), 0.03);
    EXPECT_LT(d.mean_abs, 0.05);
}
