// SPDX-License-Identifier: Apache-2.0
// Cloud density sources: the procedural layer (determinism, tiling, bounds, majorants) and
// OpenVDB volumes (sampling, transforms, empty-space skipping, and every bad input).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "cloud_test_util.hpp"
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/noise.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/vdb.hpp"

using namespace welkin;
using welkin::test::TempDir;

namespace {

// Every point of a ray where sigma_t > 0 lies in a segment whose majorant bounds it.
void expect_segments_bound(const CloudDensity& density, const CloudRay& ray, double t_max, int samples,
                           std::mt19937_64& gen) {
    std::vector<MajorantSegment> segs;
    density.segments(ray, t_max, segs);
    for (std::size_t i = 1; i < segs.size(); ++i) EXPECT_LE(segs[i - 1].t1, segs[i].t0 + 1e-9);
    std::uniform_real_distribution<double> U(0.0, t_max);
    for (int k = 0; k < samples; ++k) {
        const double t = U(gen);
        const double s = density.sigma_t(ray.at(t));
        if (s <= 0.0) continue;
        bool inside = false;
        for (const auto& g : segs)
            if (t >= g.t0 - 1e-6 && t <= g.t1 + 1e-6) {
                inside = true;
                EXPECT_LE(s, g.majorant * (1.0 + 1e-6)) << "t = " << t;
            }
        EXPECT_TRUE(inside) << "sigma_t = " << s << " at t = " << t << " outside every segment";
    }
}

CloudLayerParams tile_params() {
    CloudLayerParams p;
    p.bottom_altitude_m = 1500.0;
    p.top_altitude_m = 3000.0;
    p.base_scale_m = 1000.0;
    p.detail_scale_m = 500.0;
    p.weather_scale_m = 2000.0;
    p.coverage = 0.8;
    p.coverage_measure = CloudCoverageMeasure::area;  // the share of cloudy points below assumes it
    p.density_per_m = 0.02;
    return p;
}

}  // namespace

TEST(CloudNoise, TileableAndDeterministic) {
    for (double x : {0.13, 0.77}) {
        for (int f : {4, 8}) {
            EXPECT_NEAR(tileable_worley(x, 0.3, 0.9, f, 7),
                        tileable_worley(x + 1.0, 0.3 - 2.0, 0.9 + 3.0, f, 7), 1e-12);
            EXPECT_NEAR(tileable_perlin(x, 0.3, 0.9, f, 7),
                        tileable_perlin(x + 1.0, 0.3 - 2.0, 0.9 + 3.0, f, 7), 1e-12);
            EXPECT_EQ(tileable_worley(x, 0.3, 0.9, f, 7), tileable_worley(x, 0.3, 0.9, f, 7));
        }
        EXPECT_NE(tileable_worley(x, 0.3, 0.9, 4, 7), tileable_worley(x, 0.3, 0.9, 4, 8));
        const double w = tileable_worley(x, 0.3, 0.9, 4, 7);
        EXPECT_GE(w, 0.0);
        EXPECT_LE(w, 1.0);
    }
}

// The bake hashes each lattice once and reads the table; every texel must be the same bits
// as the header's formulas evaluated from the per-point functions (which hash per cell).
TEST(CloudNoise, BakeEqualsThePerPointFunctions) {
    const std::uint64_t seed = 5;
    const int n = 8;
    const CloudNoiseTextures t = CloudNoiseTextures::bake(seed, n, n, n, n);
    const auto worley_fbm = [&](double x, double y, double z, int f0, std::uint64_t s) {
        return 0.625 * tileable_worley(x, y, z, f0, s) + 0.25 * tileable_worley(x, y, z, 2 * f0, s + 1) +
               0.125 * tileable_worley(x, y, z, 4 * f0, s + 2);
    };
    const auto perlin_fbm = [&](double x, double y, double z, int f0, std::uint64_t s) {
        double sum = 0.0, amp = 0.5, norm = 0.0;
        for (int o = 0; o < 3; ++o, amp *= 0.5) {
            sum += amp * tileable_perlin(x, y, z, f0 << o, s + std::uint64_t(o));
            norm += amp;
        }
        return std::clamp(0.5 + 0.5 * sum / norm * 1.4, 0.0, 1.0);
    };
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double x = (i + 0.5) / n, y = (j + 0.5) / n, z = (k + 0.5) / n;
                const double w = worley_fbm(x, y, z, 4, seed * 16 + 1);
                const double p = perlin_fbm(x, y, z, 4, seed * 16 + 5);
                const glm::vec4 b = t.base.at(i, j, k), d = t.detail.at(i, j, k);
                EXPECT_EQ(b.r, float(w + p * (1.0 - w)));
                EXPECT_EQ(b.g, float(worley_fbm(x, y, z, 4, seed * 16 + 8)));
                EXPECT_EQ(b.a, float(worley_fbm(x, y, z, 16, seed * 16 + 14)));
                EXPECT_EQ(d.r, float(worley_fbm(x, y, z, 4, seed * 16 + 3)));
                EXPECT_EQ(d.b, float(worley_fbm(x, y, z, 16, seed * 16 + 9)));
                if (k == 0) {
                    EXPECT_EQ(t.weather.at(i, j, 0).r, float(perlin_fbm(x, y, 0.5 / n, 2, seed * 16 + 20)));
                    EXPECT_EQ(t.weather.at(i, j, 0).a, float(perlin_fbm(x, y, 0.5 / n, 4, seed * 16 + 32)));
                }
            }
}

TEST(ProceduralClouds, DeterministicAndSeeded) {
    const ProceduralClouds a(tile_params()), b(tile_params());
    CloudLayerParams p2 = tile_params();
    p2.seed = 2;
    const ProceduralClouds c(p2);
    const double R = a.params().planet_radius_m;
    int nonzero = 0, differ = 0;
    std::mt19937_64 gen(3);
    const CloudLayerParams& q = a.params();
    std::uniform_real_distribution<double> U(-5000.0, 5000.0), H(q.bottom_altitude_m, q.top_altitude_m);
    // 1000 points: domed cells fill about a tenth of the layer's volume at this coverage,
    // and at least 40 of the points must be cloudy for the comparisons to mean something.
    for (int k = 0; k < 1000; ++k) {
        const double x = U(gen), y = U(gen), h = H(gen);
        const glm::dvec3 at(x, y, -R + std::sqrt((R + h) * (R + h) - x * x - y * y));
        const double v = a.sigma_t(at);
        EXPECT_EQ(v, b.sigma_t(at));
        nonzero += v > 0.0;
        differ += std::abs(v - c.sigma_t(at)) > 1e-6;
    }
    EXPECT_GT(nonzero, 40);
    EXPECT_GT(differ, 40);
}

// Coverage with coverage_measure area is the share of the ground's area whose vertical
// column reaches optical depth kCoverageOpticalDepth (procedural.hpp). Measured here on
// columns of its own (random points over a square of 300 km, far from the calibration's),
// with a finer quadrature through sigma_t itself on the curved shell: within 0.1 of the
// setting for every type.
TEST(ProceduralClouds, CoverageIsTheShareOfTheAreaUnderCloud) {
    for (const auto name : kCloudTypeNames) {
        for (const double coverage : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9}) {
            CloudLayerParams p = CloudLayerParams::preset(cloud_type_from_name(name));
            p.coverage = coverage;
            p.coverage_measure = CloudCoverageMeasure::area;
            const ProceduralClouds layer(p);
            const double R = p.planet_radius_m;
            std::mt19937_64 gen(11);
            std::uniform_real_distribution<double> U(-150e3, 150e3);
            constexpr int kColumns = 600, kSteps = 64;
            int cloudy = 0;
            const double dh = (p.top_altitude_m - p.bottom_altitude_m) / kSteps;
            for (int i = 0; i < kColumns; ++i) {
                const double x = U(gen), y = U(gen);
                const glm::dvec3 up = glm::normalize(glm::dvec3(x, y, R));
                double tau = 0.0;
                for (int k = 0; k < kSteps; ++k)
                    tau += layer.sigma_t(glm::dvec3(0.0, 0.0, -R) +
                                         (R + p.bottom_altitude_m + (k + 0.5) * dh) * up) *
                           dh;
                cloudy += tau >= ProceduralClouds::kCoverageOpticalDepth;
            }
            const double measured = double(cloudy) / kColumns;
            EXPECT_NEAR(measured, coverage, 0.1) << name << " at coverage " << coverage;
            std::printf("coverage %-13s setting %.1f measured %.3f\n", std::string(name).c_str(), coverage,
                        measured);
        }
    }
}

// Coverage as the WMO's cloud amount (coverage_measure dome, procedural.hpp): the share of
// the sky dome a ground observer sees covered, measured as the renderer sees it: the fast
// march's transmittance (clouds/lighting.hpp) on 600 random directions of equal solid
// angle above 5 degrees from eight ground points (the world origin and seven 80-180 km
// away, none of the calibration's), covered where T < exp(-0.3). Their mean within 0.1 of
// the setting for every type (one observer's share varies with the weather map around
// it); the area share of the same layer printed beside it.
TEST(ProceduralClouds, DomeCoverageIsTheShareOfTheSkySeenCovered) {
    const ConstantIllumination light({0.6, 0.0, 0.8}, {1.0f}, {0.1f});
    CloudLightingOptions o;
    o.octaves = 1, o.ambient_steps = 0, o.light_steps = 1, o.shadow_grid = false;  // the transmittance only
    const double s0 = std::sin(ProceduralClouds::kDomeMinElevationDeg * M_PI / 180.0);
    for (const auto name : kCloudTypeNames) {
        for (const double coverage : {0.2, 0.5, 0.8}) {
            CloudLayerParams p = CloudLayerParams::preset(cloud_type_from_name(name));
            p.coverage = coverage;
            p.coverage_measure = CloudCoverageMeasure::dome;
            const ProceduralClouds layer(p);
            const double R = p.planet_radius_m;
            std::mt19937_64 gen(23);
            std::uniform_real_distribution<double> U(0.0, 1.0);
            double sum = 0.0;
            std::string per_observer;
            for (const glm::dvec2 g :
                 {glm::dvec2(0.0, 0.0), glm::dvec2(70e3, -40e3), glm::dvec2(-90e3, 60e3),
                  glm::dvec2(20e3, 105e3), glm::dvec2(-130e3, -75e3), glm::dvec2(150e3, 35e3),
                  glm::dvec2(-35e3, -160e3), glm::dvec2(95e3, 140e3)}) {
                const glm::dvec3 up = glm::normalize(glm::dvec3(g.x, g.y, R));
                const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0.0, 1.0, 0.0), up));
                const glm::dvec3 north = glm::cross(up, east);
                constexpr int kDirections = 600;
                std::vector<glm::dvec3> dirs(kDirections);
                for (auto& d : dirs) {
                    const double sin_el = s0 + (1.0 - s0) * U(gen), az = 2.0 * M_PI * U(gen);
                    const double cos_el = std::sqrt(1.0 - sin_el * sin_el);
                    d = sin_el * up + cos_el * (std::cos(az) * east + std::sin(az) * north);
                }
                const CloudResult r =
                    render_clouds(layer, light, glm::dvec3(0.0, 0.0, -R) + (R + 1.0) * up, dirs, o);
                int covered = 0;
                for (const float t : r.transmittance) covered += t < std::exp(-0.3);
                const double share = double(covered) / kDirections;
                sum += share;
                per_observer += fmt::format(" {:.3f}", share);
            }
            const double measured = sum / 8.0;
            EXPECT_NEAR(measured, coverage, 0.1) << name << " at coverage " << coverage;
            std::printf("dome coverage %-13s setting %.1f seen %.3f (observers%s), area share %.3f\n",
                        std::string(name).c_str(), coverage, measured, per_observer.c_str(),
                        layer.covered_fraction());
        }
    }
}

TEST(ProceduralClouds, ClearAndOvercastEnds) {
    for (const auto name : kCloudTypeNames) {
        CloudLayerParams p = CloudLayerParams::preset(cloud_type_from_name(name));
        p.coverage = 1.0;
        EXPECT_GT(ProceduralClouds(p).covered_fraction(), 0.95) << name;
    }
}

TEST(ProceduralClouds, WindShiftsTheField) {
    CloudLayerParams p = tile_params();
    const ProceduralClouds still(p);
    p.wind_offset_m = {300.0, -120.0};
    const ProceduralClouds windy(p);
    // Altitude barely changes over a few hundred metres: 300^2 / (2 R) = 7 mm.
    for (double x : {100.0, 900.0, 1700.0})
        for (double z : {1800.0, 2300.0}) {
            const double a = windy.sigma_t({x + 300.0, 40.0 - 120.0, z});
            const double b = still.sigma_t({x, 40.0, z});
            EXPECT_NEAR(a, b, 2e-3 * 0.02);
        }
}

// The wind translates the field and nothing else: the calibrated coverage, and so the clouds
// a frame shows, do not depend on the offset, nor on which offsets the process saw before
// (the calibration is cached without the wind). A keyed wind rendered with `-a` must give
// each frame what a render of that frame alone gives.
// The evolution moves the noise through the layer's height: 300 m reshapes the field (not
// a shift: the coverage stays the setting's), and the least common multiple of the base and
// detail tiles (the only periodic lookups in height) brings it back to float rounding.
TEST(ProceduralClouds, EvolutionReshapesInPlaceAndCycles) {
    // Cumulus (base 5000 m, detail 700 m tiles), its coverage the area share checked below.
    CloudLayerParams p;
    p.coverage_measure = CloudCoverageMeasure::area;
    const ProceduralClouds still(p);
    p.evolution_m = 300.0;
    const ProceduralClouds moved(p);
    p.evolution_m = 35000.0;
    const ProceduralClouds cycled(p);
    std::mt19937_64 gen(5);
    std::uniform_real_distribution<double> U(-20e3, 20e3), Z(1250.0, 3150.0);
    double diff = 0.0, mean = 0.0, worst_cycle = 0.0;
    for (int i = 0; i < 4000; ++i) {
        const glm::dvec3 x(U(gen), U(gen), Z(gen));
        const double a = still.sigma_t(x), b = moved.sigma_t(x), c = cycled.sigma_t(x);
        diff += std::abs(a - b);
        mean += a;
        worst_cycle = std::max(worst_cycle, std::abs(a - c));
    }
    EXPECT_GT(diff, 0.3 * mean);                       // reshaped
    EXPECT_LT(worst_cycle, 1e-4 * p.density_per_m);    // cycled back
    EXPECT_NEAR(moved.covered_fraction(), 0.4, 0.05);  // same coverage
}

TEST(ProceduralClouds, CoverageDoesNotDependOnTheWind) {
    CloudLayerParams p = tile_params();
    p.coverage_measure = CloudCoverageMeasure::dome;  // the default's calibration (observers in the field)
    p.seed = 9103;  // a layer no other test builds: its calibration is made here
    p.wind_offset_m = {3000.0, -1700.0};
    const ProceduralClouds windy(p);
    p.wind_offset_m = {0.0, 0.0};
    const ProceduralClouds still(p);
    EXPECT_EQ(windy.covered_fraction(4096), still.covered_fraction(4096));
}

TEST(ProceduralClouds, ZeroOutsideTheLayerAndWithoutCoverage) {
    CloudLayerParams p = tile_params();
    const ProceduralClouds layer(p);
    for (double x : {0.0, 333.0, 2500.0}) {
        EXPECT_EQ(layer.sigma_t({x, 0.0, 1400.0}), 0.0);
        EXPECT_EQ(layer.sigma_t({x, 0.0, 3100.0}), 0.0);
    }
    p.coverage = 0.0;
    const ProceduralClouds clear(p);
    std::vector<MajorantSegment> segs;
    clear.segments({{0, 0, 0}, {0, 0, 1}}, 1e6, segs);
    EXPECT_TRUE(segs.empty());
    for (double z = 1500.0; z < 3000.0; z += 37.0) EXPECT_EQ(clear.sigma_t({17.0, 5.0, z}), 0.0);
    for (const auto name : kCloudTypeNames)
        for (double f : {-0.1, 0.0, 1.0, 1.5})
            EXPECT_EQ(ProceduralClouds::height_gradient(cloud_type_from_name(name), f), 0.0);
    EXPECT_NEAR(ProceduralClouds::height_gradient(CloudType::cumulus, 0.3), 1.0, 1e-12);
    // Cumulus has a flat base: full density 4 % of the way up.
    EXPECT_NEAR(ProceduralClouds::height_gradient(CloudType::cumulus, 0.04), 1.0, 1e-12);
}

TEST(ProceduralClouds, SegmentsCoverTheDensityAndBoundIt) {
    const ProceduralClouds layer(tile_params());
    std::mt19937_64 gen(11);
    std::vector<MajorantSegment> segs;
    // Straight up: exactly the layer's thickness.
    layer.segments({{0, 0, 0}, {0, 0, 1}}, 1e6, segs);
    ASSERT_EQ(segs.size(), 1u);
    EXPECT_NEAR(segs[0].t0, 1500.0, 1e-6);
    EXPECT_NEAR(segs[0].t1, 3000.0, 1e-6);
    // From inside the layer, looking down past the ground: stops at the bottom of the layer.
    layer.segments({{0, 0, 2000}, glm::normalize(glm::dvec3(1, 0, -0.2))}, 1e6, segs);
    ASSERT_EQ(segs.size(), 1u);
    EXPECT_NEAR(segs[0].t0, 0.0, 1e-9);
    for (const glm::dvec3 d :
         {glm::dvec3(1, 0, 0.05), glm::dvec3(0.3, 1, 0.2), glm::dvec3(0, 0, 1), glm::dvec3(1, 1, 0.6)})
        expect_segments_bound(layer, {{0, 0, 0}, glm::normalize(d)}, 40000.0, 4000, gen);
}

namespace welkin {
// The whole shape, without the clear-air tests (procedural.hpp's `skip`).
struct ProceduralCloudsTestAccess {
    static double full_sigma_t(const ProceduralClouds& layer, const glm::dvec3& p) {
        const double h = glm::length(p - layer.centre_) - layer.p_.planet_radius_m;
        return layer.p_.density_per_m * layer.density(p, h, layer.k_, false);
    }
    static std::pair<double, double> band(const ProceduralClouds& layer) {
        return {layer.band_lo_, layer.band_hi_};
    }
};
}  // namespace welkin

// The clear-air tests skip lookups only: at every point sigma_t is the whole shape's value,
// for every type, its own layer and a thicker, a thinner and a coarser one; and they skip
// something (the cells' domes and the cirrus's foot leave part of the layer empty).
TEST(ProceduralClouds, ClearAirSkipsKeepEveryValue) {
    std::mt19937_64 gen(29);
    for (const auto name : kCloudTypeNames) {
        const CloudLayerParams preset = CloudLayerParams::preset(cloud_type_from_name(name));
        for (int variant = 0; variant < 4; ++variant) {
            CloudLayerParams p = preset;
            p.coverage_measure = CloudCoverageMeasure::area;  // a quick calibration
            const double thick = p.top_altitude_m - p.bottom_altitude_m;
            if (variant == 1) p.top_altitude_m = p.bottom_altitude_m + 3.0 * thick;
            if (variant == 2) p.top_altitude_m = p.bottom_altitude_m + 0.3 * thick;
            if (variant == 3) p.base_scale_m *= 4.0, p.coverage = 0.9;
            const ProceduralClouds layer(p);
            std::uniform_real_distribution<double> X(-3.0 * p.weather_scale_m, 3.0 * p.weather_scale_m);
            std::uniform_real_distribution<double> F(-0.01, 1.01);
            // Half the points near the band's ends, where a wrong bound would cut cloud.
            const double lo = ProceduralCloudsTestAccess::band(layer).first,
                         hi = ProceduralCloudsTestAccess::band(layer).second;
            std::uniform_real_distribution<double> E(-0.03, 0.03);
            int cloudy = 0;
            for (int i = 0; i < 20000; ++i) {
                const double f = i % 2 ? F(gen) : (i % 4 ? lo : hi) + E(gen);
                const glm::dvec3 x{X(gen), X(gen),
                                   p.bottom_altitude_m + f * (p.top_altitude_m - p.bottom_altitude_m)};
                const double full = ProceduralCloudsTestAccess::full_sigma_t(layer, x);
                ASSERT_EQ(layer.sigma_t(x), full) << name << " variant " << variant << " at f = " << f;
                cloudy += full > 0.0;
            }
            EXPECT_GT(cloudy, 100) << name << " variant " << variant;  // the test saw cloud
        }
    }
}

TEST(ProceduralClouds, RejectsBadParameters) {
    const auto bad = [](auto edit, const char* name) {
        CloudLayerParams p;
        edit(p);
        try {
            ProceduralClouds c(p);
            ADD_FAILURE() << name << " accepted";
        } catch (const InvalidArgument& e) {
            EXPECT_EQ(e.parameter(), name);
        }
    };
    bad([](CloudLayerParams& p) { p.coverage = 1.5; }, "coverage");
    bad([](CloudLayerParams& p) { p.top_altitude_m = 1000.0; }, "top_altitude_m");
    bad([](CloudLayerParams& p) { p.density_per_m = -1.0; }, "density_per_m");
    bad([](CloudLayerParams& p) { p.base_scale_m = std::nan(""); }, "base_scale_m");
    bad([](CloudLayerParams& p) { p.wind_offset_m.x = INFINITY; }, "wind_offset_m[0]");
    bad([](CloudLayerParams& p) { p.evolution_m = NAN; }, "evolution_m");
}

// --- OpenVDB -----------------------------------------------------------------------

namespace {

float ball(int i, int j, int k, int radius) {
    const double r = std::sqrt(double(i * i + j * j + k * k)) / radius;
    return r < 1.0 ? float(1.0 - r * r) : 0.0f;
}

template <class E>
std::string expect_throw_message(const std::function<void()>& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
        return {};
    }
    ADD_FAILURE() << "no exception";
    return {};
}

}  // namespace

TEST(VdbClouds, SamplesThroughBothTransforms) {
    TempDir dir;
    const std::string path = dir.file("ball.vdb");
    test::write_vdb(path, {test::make_float_grid("density", 10.0, 12,
                                                 [](int i, int j, int k) { return ball(i, j, k, 10); })});
    VdbCloudOptions o;
    // Blender's object matrix: scale 2, then move to (100, 2000, 800).
    o.matrix_world = glm::translate(glm::dmat4(1.0), glm::dvec3(100, 2000, 800)) *
                     glm::scale(glm::dmat4(1.0), glm::dvec3(2.0));
    o.density_scale = 0.05;
    // The closed forms below are OpenVDB's convention (value ijk at index ijk), so this test
    // asks for that placement explicitly; BlenderPlacementIsOpenVdbMovedHalfAVoxel relates
    // the default (Blender's) to it.
    o.placement = VdbCloudOptions::VoxelPlacement::OpenVdb;
    const VdbClouds v(path, o);
    EXPECT_EQ(v.negative_voxel_count(), 0u);
    EXPECT_TRUE(v.warning().empty());
    EXPECT_NEAR(v.feature_size_m(), 20.0, 1e-9);
    // Voxel (i, j, k) sits at index (i, j, k) -> object 10 (i, j, k) -> world 20 (i, j, k) + t.
    for (const auto& c : {glm::ivec3(0, 0, 0), glm::ivec3(3, -2, 5), glm::ivec3(-7, 1, 0)}) {
        const glm::dvec3 w = glm::dvec3(100, 2000, 800) + 20.0 * glm::dvec3(c);
        EXPECT_NEAR(v.sigma_t(w), 0.05 * ball(c.x, c.y, c.z, 10), 1e-7);
    }
    // Halfway between two voxel centres: the mean (trilinear).
    const glm::dvec3 mid = glm::dvec3(100, 2000, 800) + 20.0 * glm::dvec3(2.5, 0, 0);
    EXPECT_NEAR(v.sigma_t(mid), 0.05 * 0.5 * (ball(2, 0, 0, 10) + ball(3, 0, 0, 10)), 1e-7);
    EXPECT_EQ(v.sigma_t({100, 2000, 800 + 20.0 * 11.5}), 0.0);
    // Empty-space skipping: segments cover every non-zero sample, and a ray that passes far
    // away gets none.
    std::mt19937_64 gen(5);
    for (const glm::dvec3 d : {glm::dvec3(100, 2000, 800), glm::dvec3(130, 2000, 760), glm::dvec3(0, 1, 0.4)})
        expect_segments_bound(v, {{0, 0, 0}, glm::normalize(d)}, 5000.0, 4000, gen);
    std::vector<MajorantSegment> segs;
    v.segments({{0, 0, 0}, {0, 0, 1}}, 1e6, segs);
    EXPECT_TRUE(segs.empty());
    v.segments({{0, 0, 0}, glm::normalize(glm::dvec3(100, 2000, 800))}, 1e6, segs);
    ASSERT_FALSE(segs.empty());
    double covered = 0.0;
    for (const auto& g : segs) covered += g.t1 - g.t0;
    EXPECT_LT(covered, 2.0 * 20.0 * 2 * 12 * 1.8);  // no more than the grid's (dilated) diagonal
}

// Blender's placement (the default) is OpenVDB's moved by +1/2 voxel along every index
// axis, through both transforms: with index_to_world = matrix_world * grid_transform (linear
// part A), every world point p of the OpenVDB placement reads the same density at
// p + A (1/2, 1/2, 1/2) in Blender's; the majorant segments of a ray moved by that offset
// are the same (same t, same majorants), and so are the world bounds, moved. The matrix
// rotates and scales non-uniformly so that the offset is not along a world axis.
// The grid comes back from the reader process (clouds/vdb.cpp, GridPipe) as the file holds
// it: active tiles at each internal level (8^3 and 128^3 voxels), an inactive tile and
// inactive voxels with values that are not the background (samplers read them too), leaf
// voxels, and an affine transform that is not a plain scale. Every sample, through
// trilinear interpolation, equals OpenVDB's own sampler on the grid as written.
TEST(VdbClouds, TheReaderProcessReturnsTheGridAsTheFileHoldsIt) {
    TempDir dir;
    const std::string path = dir.file("tiles.vdb");
    const openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
    g->setName("density");
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.preScale(openvdb::Vec3d(10.0, 12.0, 8.0));
    m.postRotate(openvdb::math::Z_AXIS, 0.3);
    m.postTranslate(openvdb::Vec3d(5.0, -20.0, 40.0));
    g->setTransform(openvdb::math::Transform::createLinearTransform(m));
    g->tree().addTile(2, openvdb::Coord(128, 0, 0), 0.25f, true);  // 128^3 voxels
    g->tree().addTile(1, openvdb::Coord(0, 0, 16), 0.5f, true);    // 8^3
    g->tree().addTile(1, openvdb::Coord(0, 0, 24), 0.75f, false);  // inactive, not background
    auto acc = g->getAccessor();
    for (int i = -6; i < 10; ++i)
        for (int j = -3; j < 7; ++j)
            for (int k = 0; k < 12; ++k) {
                const float v = 0.1f + 0.01f * float(i + 2 * j + 3 * k);
                if ((i + j + k) % 5 == 0)
                    acc.setValueOff(openvdb::Coord(i, j, k), v);
                else
                    acc.setValueOn(openvdb::Coord(i, j, k), v);
            }
    test::write_vdb(path, {g});
    VdbCloudOptions o;
    o.placement = VdbCloudOptions::VoxelPlacement::OpenVdb;
    const VdbClouds v(path, o);
    std::mt19937_64 gen(11);
    std::uniform_real_distribution<double> u(-10.0, 270.0), w(-8.0, 40.0);
    const auto cacc = g->getConstAccessor();
    int checked = 0;
    for (int n = 0; n < 4000; ++n) {
        const openvdb::Vec3d index(u(gen), w(gen), w(gen));
        const openvdb::Vec3d world = g->transform().indexToWorld(index);
        const double expected = std::max(0.0, double(openvdb::tools::BoxSampler::sample(cacc, index)));
        ASSERT_NEAR(v.sigma_t({world.x(), world.y(), world.z()}), expected, 1e-6) << index;
        checked += expected > 0.0;
    }
    EXPECT_GT(checked, 1000);
}

TEST(VdbClouds, BlenderPlacementIsOpenVdbMovedHalfAVoxel) {
    TempDir dir;
    const std::string path = dir.file("ball.vdb");
    const double voxel = 10.0;
    test::write_vdb(path, {test::make_float_grid("density", voxel, 12, [](int i, int j, int k) {
                        return ball(i - 1, j + 2, k, 9) * float(1.0 + 0.05 * i);
                    })});
    VdbCloudOptions o;
    o.matrix_world = glm::translate(glm::dmat4(1.0), glm::dvec3(-300, 1500, 900)) *
                     glm::rotate(glm::dmat4(1.0), 0.7, glm::normalize(glm::dvec3(1, 2, 3))) *
                     glm::scale(glm::dmat4(1.0), glm::dvec3(1.5, 2.0, 0.8));
    o.density_scale = 0.04;
    EXPECT_EQ(o.placement, VdbCloudOptions::VoxelPlacement::Blender);  // the default
    const VdbClouds blender(path, o);
    o.placement = VdbCloudOptions::VoxelPlacement::OpenVdb;
    const VdbClouds openvdb(path, o);
    const glm::dvec3 offset = glm::dmat3(o.matrix_world) * glm::dvec3(0.5 * voxel);
    // Voxel (i, j, k): in OpenVDB's placement at matrix_world (10 (i, j, k)), in Blender's at
    // matrix_world (10 (i + 1/2, j + 1/2, k + 1/2)).
    for (const auto& c : {glm::ivec3(1, -2, 0), glm::ivec3(4, 0, -3), glm::ivec3(-5, -1, 2)}) {
        const glm::dvec3 at_openvdb = glm::dvec3(o.matrix_world * glm::dvec4(voxel * glm::dvec3(c), 1.0));
        const double expected = 0.04 * ball(c.x - 1, c.y + 2, c.z, 9) * (1.0 + 0.05 * c.x);
        ASSERT_GT(expected, 0.0);
        EXPECT_NEAR(openvdb.sigma_t(at_openvdb), expected, 1e-7);
        EXPECT_NEAR(blender.sigma_t(at_openvdb + offset), expected, 1e-7);
        EXPECT_GT(std::abs(blender.sigma_t(at_openvdb) - expected), 1e-5);  // not where OpenVDB puts it
    }
    std::mt19937_64 gen(11);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    const glm::dvec3 centre(-300, 1500, 900);
    for (int n = 0; n < 2000; ++n) {
        const glm::dvec3 p = centre + 160.0 * glm::dvec3(U(gen), U(gen), U(gen));
        EXPECT_NEAR(blender.sigma_t(p + offset), openvdb.sigma_t(p), 1e-9);
    }
    for (int n = 0; n < 50; ++n) {
        const glm::dvec3 origin = centre + glm::dvec3(2000.0 * U(gen), 2000.0 * U(gen), 2000.0 * U(gen));
        const glm::dvec3 dir = glm::normalize(centre + 100.0 * glm::dvec3(U(gen), U(gen), U(gen)) - origin);
        std::vector<MajorantSegment> a, b;
        openvdb.segments({origin, dir}, 5000.0, a);
        blender.segments({origin + offset, dir}, 5000.0, b);
        ASSERT_EQ(a.size(), b.size());
        for (std::size_t s = 0; s < a.size(); ++s) {
            EXPECT_NEAR(a[s].t0, b[s].t0, 1e-6);
            EXPECT_NEAR(a[s].t1, b[s].t1, 1e-6);
            EXPECT_EQ(a[s].majorant, b[s].majorant);
        }
        // And the Blender placement's segments still bound its own density.
        expect_segments_bound(blender, {origin, dir}, 5000.0, 200, gen);
    }
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(blender.world_bounds_min()[a], openvdb.world_bounds_min()[a] + offset[a], 1e-6);
        EXPECT_NEAR(blender.world_bounds_max()[a], openvdb.world_bounds_max()[a] + offset[a], 1e-6);
    }
}

TEST(VdbClouds, MissingFile) {
    const std::string m = expect_throw_message<IoError>([] { VdbClouds v("/nonexistent/welkin/cloud.vdb"); });
    EXPECT_NE(m.find("/nonexistent/welkin/cloud.vdb"), std::string::npos) << m;
    EXPECT_NE(m.find("density"), std::string::npos) << m;
}

TEST(VdbClouds, CorruptFile) {
    TempDir dir;
    const std::string garbage = dir.file("garbage.vdb");
    {
        std::ofstream f(garbage, std::ios::binary);
        for (int i = 0; i < 4096; ++i) f.put(char((i * 7919) & 0xff));
    }
    std::string m = expect_throw_message<IoError>([&] { VdbClouds v(garbage); });
    EXPECT_NE(m.find(garbage), std::string::npos) << m;
    // A valid file cut short.
    const std::string good = dir.file("good.vdb"), cut = dir.file("cut.vdb");
    test::write_vdb(good, {test::make_float_grid("density", 1.0, 12,
                                                 [](int i, int j, int k) { return ball(i, j, k, 12); })});
    {
        std::ifstream in(good, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), {});
        std::ofstream out(cut, std::ios::binary);
        out.write(bytes.data(), std::streamsize(bytes.size() * 2 / 3));
    }
    m = expect_throw_message<IoError>([&] { VdbClouds v(cut); });
    EXPECT_NE(m.find(cut), std::string::npos) << m;
}

TEST(VdbClouds, NoSuchGridListsTheGrids) {
    TempDir dir;
    const std::string path = dir.file("smoke.vdb");
    test::write_vdb(path, {test::make_float_grid("smoke", 1.0, 3, [](int, int, int) { return 1.0f; }),
                           test::make_float_grid("temperature", 1.0, 3, [](int, int, int) { return 1.0f; })});
    const std::string m = expect_throw_message<InvalidArgument>([&] { VdbClouds v(path); });
    for (const char* s : {"'density'", "'smoke'", "'temperature'"})
        EXPECT_NE(m.find(s), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
    VdbCloudOptions o;
    o.grid = "smoke";
    EXPECT_NO_THROW(VdbClouds(path, o));
}

TEST(VdbClouds, WrongGridType) {
    TempDir dir;
    const std::string path = dir.file("velocity.vdb");
    auto grid = openvdb::Vec3SGrid::create();
    grid->setName("density");
    grid->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
    test::write_vdb(path, {grid});
    const std::string m = expect_throw_message<InvalidArgument>([&] { VdbClouds v(path); });
    EXPECT_NE(m.find("FloatGrid"), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find("'density'"), std::string::npos) << m;
}

// A frustum (non-affine) transform is refused by name, after the reader process.
TEST(VdbClouds, FrustumTransformRefused) {
    TempDir dir;
    const std::string path = dir.file("frustum.vdb");
    const openvdb::FloatGrid::Ptr g = openvdb::FloatGrid::create(0.0f);
    g->setName("density");
    g->setTransform(openvdb::math::Transform::createFrustumTransform(
        openvdb::BBoxd(openvdb::Vec3d(0, 0, 0), openvdb::Vec3d(10, 10, 10)), 0.5, 100.0, 1.0));
    g->getAccessor().setValue(openvdb::Coord(1, 2, 3), 0.5f);
    test::write_vdb(path, {g});
    const std::string m = expect_throw_message<InvalidArgument>([&] { VdbClouds v(path); });
    EXPECT_NE(m.find("frustum"), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
}

TEST(VdbClouds, EmptyGrid) {
    TempDir dir;
    const std::string path = dir.file("empty.vdb");
    test::write_vdb(path, {test::make_float_grid("density", 1.0, 2, [](int, int, int) { return 0.0f; })});
    const std::string m = expect_throw_message<InvalidArgument>([&] { VdbClouds v(path); });
    EXPECT_NE(m.find("empty"), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
}

TEST(VdbClouds, NegativeDensitiesClampedAndCountedOrRejected) {
    TempDir dir;
    const std::string path = dir.file("negative.vdb");
    test::write_vdb(path, {test::make_float_grid("density", 1.0, 3,
                                                 [](int i, int, int) { return i < 0 ? -0.5f : 1.0f; })});
    const VdbClouds v(path);
    EXPECT_EQ(v.negative_voxel_count(), 3u * 7u * 7u);
    EXPECT_NE(v.warning().find(path), std::string::npos) << v.warning();
    EXPECT_EQ(v.sigma_t({-2.0, 0.0, 0.0}), 0.0);
    EXPECT_NEAR(v.sigma_t({2.0, 0.0, 0.0}), 1.0, 1e-7);
    VdbCloudOptions o;
    o.negative = VdbCloudOptions::Negative::Reject;
    const std::string m = expect_throw_message<InvalidArgument>([&] { VdbClouds r(path, o); });
    EXPECT_NE(m.find("negative"), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
}

TEST(VdbClouds, HugeGridRefusedBeforeReading) {
    TempDir dir;
    const std::string path = dir.file("big.vdb");
    test::write_vdb(path, {test::make_float_grid("density", 1.0, 20, [](int, int, int) { return 1.0f; })});
    VdbCloudOptions o;
    o.max_memory_bytes = 64 * 1024;  // 41^3 voxels * 4 B = 270 KiB > 64 KiB
    const std::string m = expect_throw_message<InvalidArgument>([&] { VdbClouds v(path, o); });
    EXPECT_NE(m.find("MiB"), std::string::npos) << m;
    EXPECT_NE(m.find(path), std::string::npos) << m;
    o.max_memory_bytes = std::uint64_t(1) << 30;
    EXPECT_NO_THROW(VdbClouds(path, o));
}

TEST(VdbClouds, OtherBadInput) {
    TempDir dir;
    // A background that would fill space.
    const std::string bg = dir.file("background.vdb");
    auto g = openvdb::FloatGrid::create(0.5f);
    g->setName("density");
    g->getAccessor().setValue(openvdb::Coord(0, 0, 0), 1.0f);
    test::write_vdb(bg, {g});
    EXPECT_NE(expect_throw_message<InvalidArgument>([&] { VdbClouds v(bg); }).find("background"),
              std::string::npos);
    // A NaN voxel.
    const std::string nan = dir.file("nan.vdb");
    test::write_vdb(
        nan, {test::make_float_grid("density", 1.0, 2, [](int i, int, int) { return i == 0 ? NAN : 1.0f; })});
    EXPECT_NE(expect_throw_message<InvalidArgument>([&] { VdbClouds v(nan); }).find("non-finite"),
              std::string::npos);
    // A singular object matrix, a bad density scale.
    const std::string ok = dir.file("ok.vdb");
    test::write_vdb(ok, {test::make_float_grid("density", 1.0, 2, [](int, int, int) { return 1.0f; })});
    VdbCloudOptions o;
    o.matrix_world = glm::scale(glm::dmat4(1.0), glm::dvec3(1.0, 0.0, 1.0));
    try {
        VdbClouds v(ok, o);
        ADD_FAILURE();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "matrix_world");
    }
    o = {};
    o.density_scale = -1.0;
    EXPECT_THROW(VdbClouds(ok, o), InvalidArgument);
    o = {};
    o.grid = "";
    EXPECT_THROW(VdbClouds(ok, o), InvalidArgument);
}

TEST(ProceduralClouds, TypeNamesAndErrors) {
    for (std::size_t i = 0; i < kCloudTypeNames.size(); ++i) {
        const CloudType t = cloud_type_from_name(kCloudTypeNames[i]);
        EXPECT_EQ(cloud_type_name(t), kCloudTypeNames[i]);
        EXPECT_EQ(CloudLayerParams::preset(t).cloud_type, t);
        EXPECT_NO_THROW(CloudLayerParams::preset(t).validate());
    }
    const std::string m =
        expect_throw_message<InvalidArgument>([] { cloud_type_from_name("nimbus", "layers[0].cloud_type"); });
    EXPECT_NE(m.find("layers[0].cloud_type"), std::string::npos) << m;
    for (const auto n : kCloudTypeNames) EXPECT_NE(m.find(std::string(n)), std::string::npos) << m;
    EXPECT_NE(m.find("nimbus"), std::string::npos) << m;
    for (const auto n : kCoverageMeasureNames)
        EXPECT_EQ(coverage_measure_name(coverage_measure_from_name(n)), n);
    const std::string mm = expect_throw_message<InvalidArgument>(
        [] { coverage_measure_from_name("oktas", "layers[0].coverage_measure"); });
    EXPECT_NE(mm.find("layers[0].coverage_measure"), std::string::npos) << mm;
    EXPECT_NE(mm.find("dome"), std::string::npos) << mm;
    EXPECT_NE(mm.find("oktas"), std::string::npos) << mm;
}
