// SPDX-License-Identifier: Apache-2.0
// The upsampled cloud pass (render_clouds_grid, CloudUpsampling in lighting.hpp): the rays
// it marches are the plain march's rays bit for bit (with the footprint `finest` pixels
// wide where one is set); every other ray is the bilinear
// combination of the four marched corners of the one block that owns it; zero tolerances
// with a finest block of one pixel march every ray that differs (the plain march); the
// result does not depend on the thread count; the block-size limit splits blocks that
// span more than it at their cloud's distance, however well their corners agree; the
// automatic stride halves every block evenly; blocks are about square in angle (an
// equirect's near a pole wider in pixels); rays ending at geometry are not interpolated
// across its silhouette.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/procedural.hpp"

using namespace welkin;
using welkin::test::HomogeneousBox;
using welkin::test::sky_grid;

namespace {

const ConstantIllumination& light() {
    static const ConstantIllumination l(glm::normalize(glm::dvec3(0.6, 0.2, 0.5)), {1.0f, 0.9f, 0.8f},
                                        {0.1f, 0.15f, 0.25f});
    return l;
}

const glm::dvec3 kEye(0.0);

CloudLightingOptions quick() {
    CloudLightingOptions o;
    o.max_steps = 32;
    return o;
}

CloudUpsampling settings(int stride, int finest, double dT, double dL, double block) {
    CloudUpsampling u;
    u.stride = stride, u.finest = finest, u.transmittance_tolerance = dT, u.radiance_tolerance = dL;
    u.max_block_size_m = block;
    return u;
}

// The same radiances, transmittances and depths, bit for bit.
void expect_same(const CloudResult& a, const CloudResult& b) {
    EXPECT_EQ(a.radiance, b.radiance);
    EXPECT_EQ(a.transmittance, b.transmittance);
    EXPECT_EQ(a.depth_m, b.depth_m);
}

}  // namespace

TEST(CloudUpsampling, StrideOneIsThePlainMarch) {
    const int W = 64, H = 24;
    const ProceduralClouds layer(CloudLayerParams{});
    const auto dirs = sky_grid(W, H);
    const CloudResult plain = render_clouds(layer, light(), glm::dvec3(0.0), dirs, quick());
    const CloudResult grid = render_clouds_grid(layer, light(), glm::dvec3(0.0), dirs, W, quick(),
                                                settings(1, 1, 0.1, 0.3, 500.0));
    EXPECT_TRUE(grid.interpolation.all_marched());
    expect_same(grid, plain);
}

// The default layer from the ground at stride 8: the marched rays are the plain march's
// (same seeds), each other ray is owned by exactly one block, whose corners are marched,
// and is their bilinear combination (so within their range).
TEST(CloudUpsampling, MarchedRaysAreThePlainMarchAndTheRestTheirBlocksCorners) {
    const int W = 160, H = 64;
    const ProceduralClouds layer(CloudLayerParams{});
    const auto dirs = sky_grid(W, H);
    const CloudResult plain = render_clouds(layer, light(), glm::dvec3(0.0), dirs, quick());
    const CloudResult grid = render_clouds_grid(layer, light(), glm::dvec3(0.0), dirs, W, quick(),
                                                settings(8, 2, 0.1, 0.3, 500.0));
    const CloudGridInterpolation& g = grid.interpolation;
    ASSERT_EQ(g.marched.size(), dirs.size());
    std::size_t marched = 0, cloudy = 0;
    for (std::size_t p = 0; p < dirs.size(); ++p) {
        if (!g.marched[p]) continue;
        ++marched;
        cloudy += plain.transmittance[p] < 1.0f;
        ASSERT_EQ(grid.transmittance[p], plain.transmittance[p]) << p;
        ASSERT_EQ(grid.depth_m[p], plain.depth_m[p]) << p;
        for (int c = 0; c < 3; ++c) ASSERT_EQ(grid.radiance[p * 3 + c], plain.radiance[p * 3 + c]) << p;
    }
    // Some rays interpolated, some refined beyond the coarse lattice (21 x 9 rays), clouds met.
    EXPECT_LT(marched, dirs.size() * 3 / 4);
    EXPECT_GT(marched, std::size_t(21 * 9));
    EXPECT_GT(cloudy, std::size_t(20));
    std::vector<int> visits(dirs.size(), 0);
    // for_each_interpolated runs in parallel; each pixel is visited once, so the writes
    // to visits[p] do not race.
    g.for_each_interpolated([&](std::size_t p, const std::size_t q[4], const double w[4]) {
        ++visits[p];
        double sum_w = 0.0, T = 0.0;
        float lo = 2.0f, hi = -1.0f;
        for (int a = 0; a < 4; ++a) {
            EXPECT_TRUE(g.marched[q[a]]) << p;
            EXPECT_GE(w[a], 0.0);
            sum_w += w[a];
            T += w[a] * grid.transmittance[q[a]];
            lo = std::min(lo, grid.transmittance[q[a]]);
            hi = std::max(hi, grid.transmittance[q[a]]);
        }
        EXPECT_NEAR(sum_w, 1.0, 1e-12);
        EXPECT_NEAR(grid.transmittance[p], T, 1e-6);
        EXPECT_GE(grid.transmittance[p], lo - 1e-6f);
        EXPECT_LE(grid.transmittance[p], hi + 1e-6f);
    });
    for (std::size_t p = 0; p < dirs.size(); ++p) EXPECT_EQ(visits[p], g.marched[p] ? 0 : 1) << p;
    // A block is left unsplit only at the finest size or where its corners agree.
    for (const auto& b : g.blocks) EXPECT_TRUE(b.x1 > b.x0 || b.y1 > b.y0);
}

// With the rays' footprint set (an image's pixel angle), a refined grid marches each ray as
// the plain march does with a footprint `finest` pixels wide: its marched rays are at least
// that far apart, so the optical-depth grids are read at their spacing, not a pixel's
// (lighting.hpp, CloudUpsampling). Bit for bit with the plain march at finest x the angle;
// at one pixel's angle some of them differ (the grids' levels move).
TEST(CloudUpsampling, MarchedRaysStandForTheirSpacing) {
    const int W = 160, H = 64;
    CloudLayerParams p = CloudLayerParams::preset(CloudType::altocumulus);
    const ProceduralClouds layer(p);
    const auto dirs = sky_grid(W, H);
    CloudLightingOptions pixel = quick();
    pixel.ray_spread_rad = 2.0 * std::numbers::pi / W;
    for (const int finest : {2, 4}) {
        const CloudResult grid =
            render_clouds_grid(layer, light(), kEye, dirs, W, pixel, settings(8, finest, 0.1, 0.3, 500.0));
        CloudLightingOptions spaced = pixel;
        spaced.ray_spread_rad = finest * pixel.ray_spread_rad;
        const CloudResult plain = render_clouds(layer, light(), kEye, dirs, spaced);
        const CloudResult one_pixel = render_clouds(layer, light(), kEye, dirs, pixel);
        std::size_t cloudy = 0, moved = 0;
        for (std::size_t q = 0; q < dirs.size(); ++q) {
            if (!grid.interpolation.marched[q]) continue;
            ASSERT_EQ(grid.transmittance[q], plain.transmittance[q]) << q;
            for (int c = 0; c < 3; ++c) ASSERT_EQ(grid.radiance[q * 3 + c], plain.radiance[q * 3 + c]) << q;
            cloudy += plain.transmittance[q] < 0.99f;
            moved += grid.radiance[q * 3 + 1] != one_pixel.radiance[q * 3 + 1];
        }
        EXPECT_GT(cloudy, std::size_t(100)) << finest;
        EXPECT_GT(moved, cloudy / 2) << finest;
    }
}

// Tolerances 0 and a finest block of one pixel split every block whose corners differ in
// any way: the pass is the plain march. A deck over the whole view: every ray differs.
TEST(CloudUpsampling, ZeroTolerancesAreThePlainMarch) {
    const int W = 48, H = 20;
    const HomogeneousBox deck({-1e6, -1e6, 1000.0}, {1e6, 1e6, 1400.0}, 0.01);
    const auto dirs = sky_grid(W, H);
    const CloudResult plain = render_clouds(deck, light(), glm::dvec3(0.0), dirs, quick());
    const CloudResult grid =
        render_clouds_grid(deck, light(), glm::dvec3(0.0), dirs, W, quick(), settings(8, 1, 0.0, 0.0, 1e7));
    expect_same(grid, plain);
}

TEST(CloudUpsampling, ThreadCountDoesNotMatter) {
    const int W = 96, H = 40;
    const ProceduralClouds layer(CloudLayerParams{});
    const auto dirs = sky_grid(W, H);
    const CloudUpsampling up = settings(8, 2, 0.1, 0.3, 500.0);
    CloudResult one;
    tbb::task_arena(1).execute(
        [&] { one = render_clouds_grid(layer, light(), glm::dvec3(0.0), dirs, W, quick(), up); });
    const CloudResult many = render_clouds_grid(layer, light(), glm::dvec3(0.0), dirs, W, quick(), up);
    expect_same(one, many);
    EXPECT_EQ(one.interpolation.marched, many.interpolation.marched);
}

// With tolerances 1 every block's corners agree; only the block-size limit splits. The
// deck 1 km up is seen 1 to 27 km away: a limit of 0 splits every block down to the
// finest, no limit splits none, and 2 km splits the far blocks (low elevations: the
// bottom block, 24 to 3 degrees, spans about 8 km at its farthest corner) and not the
// near ones (the top block, 87 to 66 degrees, about 0.5 km).
TEST(CloudUpsampling, BlockSizeLimitSplitsBlocksWiderThanItAtTheirCloud) {
    const int W = 64, H = 33;
    const HomogeneousBox deck({-1e6, -1e6, 1000.0}, {1e6, 1e6, 1400.0}, 0.01);
    const auto dirs = sky_grid(W, H);
    const auto marched_rows = [&](double limit) {
        const CloudResult r = render_clouds_grid(deck, light(), glm::dvec3(0.0), dirs, W, quick(),
                                                 settings(8, 2, 1.0, 1.0, limit));
        std::vector<int> per_row(H, 0);
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) per_row[j] += r.interpolation.marched[std::size_t(j) * W + i];
        return per_row;
    };
    const std::vector<int> none = marched_rows(1e7), all = marched_rows(0.0), some = marched_rows(2000.0);
    int n_none = 0, n_all = 0;
    for (int j = 0; j < H; ++j) n_none += none[j], n_all += all[j];
    EXPECT_EQ(n_none, 9 * 5);   // the coarse lattice alone: columns 0, 8, .., 56, 63; rows 0, 8, .., 32
    EXPECT_EQ(n_all, 17 * 33);  // every even row, and in it every even column and the last
    EXPECT_EQ(some[4], 0);      // the top block's middle row: not split
    EXPECT_EQ(some[28], 33);    // the bottom block's: split to the finest
}

namespace {

// W columns around the sky and H rows from `bottom_deg` up, rows as far apart as the
// columns (360 / W degrees), at the pixels' centres.
std::vector<glm::dvec3> band_grid(int W, int H, double bottom_deg) {
    std::vector<glm::dvec3> d;
    const double step = 2.0 * std::numbers::pi / W;
    for (int j = 0; j < H; ++j) {
        const double el = bottom_deg * std::numbers::pi / 180.0 + (H - 0.5 - j) * step;
        for (int i = 0; i < W; ++i) {
            const double az = step * (i + 0.5);
            d.push_back({std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)});
        }
    }
    return d;
}

}  // namespace

// The automatic stride (0) is the power of two nearest width / 256, so that the quadtree
// halves every block evenly down to the finest size. A deck whose blocks are all split
// to the finest (block limit 0), 1921 rays wide (7.5 x 256): stride 8 marches every
// second column and row and no more; the stride 7 that width / 256 rounded down to
// leaves blocks of 3 and 4 pixels, halved into blocks 1 and 2 wide, and marches a third
// more rays for the same finest size.
TEST(CloudUpsampling, TheAutomaticStrideHalvesEveryBlockEvenly) {
    const CloudUpsampling automatic;
    for (const auto& [width, stride] : {std::pair{256, 1},
                                        {511, 1},
                                        {512, 2},
                                        {724, 2},
                                        {725, 4},
                                        {1024, 4},
                                        {1280, 4},
                                        {1448, 4},
                                        {1449, 8},
                                        {1920, 8},
                                        {2048, 8},
                                        {3840, 16},
                                        {16384, 16}})
        EXPECT_EQ(automatic.resolved_stride(width, width / 2), stride) << width;
    EXPECT_EQ(automatic.resolved_stride(1920, 1), 1);
    EXPECT_EQ(settings(7, 2, 0.1, 0.3, 500.0).resolved_stride(1920, 1080), 7);

    // Rows as far apart as columns (blocks square in angle: aspect 1), 10 to 13 degrees up.
    const int W = 1921, H = 17;
    const HomogeneousBox deck({-1e6, -1e6, 1000.0}, {1e6, 1e6, 1400.0}, 0.01);
    const auto dirs = band_grid(W, H, 10.0);
    const auto marched = [&](int stride) {
        const CloudResult r =
            render_clouds_grid(deck, light(), kEye, dirs, W, quick(), settings(stride, 2, 1.0, 1.0, 0.0));
        return std::count(r.interpolation.marched.begin(), r.interpolation.marched.end(), 1);
    };
    const auto even = marched(0);
    EXPECT_EQ(even, 961 * 9);  // columns 0, 2, .., 1920; rows 0, 2, .., 16
    EXPECT_GT(marched(7), even * 5 / 4);
}

// Blocks about square in angle: the upper half of an equirect sky 257 wide (rows 1.4
// degrees apart, as its columns are at the horizon; 65 rows, from 1.4 degrees up), every
// block split to the finest (2 pixels: block limit 0). Near the horizon every second
// column of every second row is marched; above 70 degrees up (the lattice rows of 8
// pixels whose lower row is above 60 degrees, where the columns are less than half as far
// apart as the rows) at most every fourth column; in all, fewer than on a lattice of
// square pixels, down to about the share of the sky's solid angle (2 / pi of it) where the
// lattice's rows are closer. Each interpolated pixel's corners are marched.
TEST(CloudUpsampling, BlocksAreAboutSquareInAngle) {
    const int W = 257, H = 65;  // the last column and row on every lattice
    const HomogeneousBox deck({-1e6, -1e6, 1000.0}, {1e6, 1e6, 1400.0}, 0.01);
    const auto dirs = band_grid(W, H, 0.7);
    const CloudResult r =
        render_clouds_grid(deck, light(), kEye, dirs, W, quick(), settings(8, 2, 1.0, 1.0, 0.0));
    const CloudGridInterpolation& g = r.interpolation;
    std::size_t total = 0;
    for (int j = 0; j < H; ++j) {
        const double el = std::asin(dirs[std::size_t(j) * W].z) * 180.0 / std::numbers::pi;
        int in_row = 0;
        for (int i = 0; i < W; ++i) in_row += g.marched[std::size_t(j) * W + i];
        total += std::size_t(in_row);
        if (j % 2 == 1 && j != H - 1) {
            EXPECT_EQ(in_row, 0) << j;
        } else if (el < 30.0) {
            EXPECT_EQ(in_row, W / 2 + 1) << j;  // columns 0, 2, .., 256
        } else if (el > 70.0) {
            EXPECT_LE(in_row, W / 4 + 1) << j;
        }
    }
    const std::size_t square = std::size_t(W / 2 + 1) * std::size_t(H / 2 + 1);
    EXPECT_LT(double(total), 0.9 * double(square));
    EXPECT_GT(double(total), 2.0 / std::numbers::pi * double(square));
    g.for_each_interpolated([&](std::size_t p, const std::size_t q[4], const double[4]) {
        for (int a = 0; a < 4; ++a) EXPECT_TRUE(g.marched[q[a]]) << p;
    });
}

// Rays with lengths (a camera's rays ending at its geometry): a deck over the whole view,
// and in front of it a disc of geometry 500 m away (a silhouette) and a tilted surface
// beyond the deck's reach (lengths varying smoothly, 200 to 240 m). Interpolation never
// crosses the silhouette: every ray inside the disc is clear (T = 1, no light), as the
// plain march gives, and every block interpolated holds rays of one kind (all unbounded,
// or all ending within the length tolerance); the sky's blocks and the smooth surface's
// are still interpolated.
TEST(CloudUpsampling, InterpolationDoesNotCrossTheGeometrysSilhouette) {
    const int W = 96, H = 64;
    const HomogeneousBox deck({-1e6, -1e6, 1000.0}, {1e6, 1e6, 1400.0}, 0.01);
    const auto dirs = sky_grid(W, H);
    std::vector<double> lengths(dirs.size(), std::numeric_limits<double>::infinity());
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const std::size_t p = std::size_t(j) * W + std::size_t(i);
            if (std::hypot(i - 30.0, j - 20.0) < 12.0) lengths[p] = 500.0;
            if (i >= 60) lengths[p] = 200.0 + 40.0 * (i - 60) / (W - 61);
        }
    const std::span<const glm::dvec3> origin(&kEye, 1);
    const CloudResult plain = render_clouds(deck, light(), origin, dirs, lengths, quick());
    const CloudResult grid =
        render_clouds_grid(deck, light(), origin, dirs, lengths, W, quick(), settings(8, 2, 0.1, 0.3, 1e7));
    const CloudGridInterpolation& g = grid.interpolation;
    ASSERT_EQ(g.marched.size(), dirs.size());
    std::size_t marched = 0, interpolated_bounded = 0;
    for (std::size_t p = 0; p < dirs.size(); ++p) {
        marched += g.marched[p];
        interpolated_bounded += !g.marched[p] && std::isfinite(lengths[p]);
        if (std::isfinite(lengths[p])) {
            EXPECT_EQ(plain.transmittance[p], 1.0f) << p;
            EXPECT_EQ(grid.transmittance[p], 1.0f) << p;
            EXPECT_EQ(grid.radiance[p * 3], 0.0f) << p;
        } else {
            EXPECT_LT(grid.transmittance[p], 0.1f) << p;  // the deck, > 400 m of sigma_t 0.01
        }
    }
    EXPECT_LT(marched, dirs.size() / 2);
    EXPECT_GT(interpolated_bounded, std::size_t(0));
    for (const auto& b : g.blocks) {
        double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
        for (int y = b.y0; y <= b.y1; ++y)
            for (int x = b.x0; x <= b.x1; ++x) {
                lo = std::min(lo, lengths[std::size_t(y) * W + std::size_t(x)]);
                hi = std::max(hi, lengths[std::size_t(y) * W + std::size_t(x)]);
            }
        EXPECT_TRUE(std::isinf(lo) || hi - lo <= CloudUpsampling::kLengthTolerance * lo)
            << b.x0 << "," << b.y0 << " " << lo << " " << hi;
    }
    // Without the lengths the same blocks would interpolate the deck over the disc.
    const CloudResult blind =
        render_clouds_grid(deck, light(), origin, dirs, {}, W, quick(), settings(8, 2, 0.1, 0.3, 1e7));
    EXPECT_LT(blind.transmittance[std::size_t(20) * W + 30], 1.0f);
}

TEST(CloudUpsampling, BadSettingsNameTheParameter) {
    const auto dirs = sky_grid(8, 4);
    const HomogeneousBox deck({-1e3, -1e3, 1000.0}, {1e3, 1e3, 1400.0}, 0.01);
    const auto parameter = [&](const CloudUpsampling& up) {
        try {
            render_clouds_grid(deck, light(), glm::dvec3(0.0), dirs, 8, quick(), up);
        } catch (const InvalidArgument& e) {
            return e.parameter();
        }
        return std::string("none");
    };
    EXPECT_EQ(parameter(settings(17, 2, 0.1, 0.3, 500.0)), "stride");
    EXPECT_EQ(parameter(settings(-1, 2, 0.1, 0.3, 500.0)), "stride");
    EXPECT_EQ(parameter(settings(8, 0, 0.1, 0.3, 500.0)), "finest");
    EXPECT_EQ(parameter(settings(8, 2, 1.5, 0.3, 500.0)), "transmittance_tolerance");
    EXPECT_EQ(parameter(settings(8, 2, 0.1, std::nan(""), 500.0)), "radiance_tolerance");
    EXPECT_EQ(parameter(settings(8, 2, 0.1, 0.3, -1.0)), "max_block_size_m");
    EXPECT_EQ(parameter(settings(8, 2, 0.1, 0.3, 500.0)), "none");
}
