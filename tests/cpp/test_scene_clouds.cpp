// SPDX-License-Identifier: Apache-2.0
// A scene's clouds: the "clouds" key of the scene JSON (round trip, defaults, errors naming
// the key, VDB paths relative to the file), and the union of density sources (sum of
// sigma_t, merged majorant segments, a closed form for two constant slabs).
#include <cmath>
#include <fstream>
#include <memory>
#include <random>
#include <string>

#include "cloud_test_util.hpp"
#include "invalid_argument_testing.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/union.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
using welkin::test::HomogeneousBox;
using welkin::test::parameter_of;

namespace {

std::string scene_with_clouds(const std::string& clouds) {
    return R"({"version": 1, "clouds": )" + clouds + "}";
}

// A list of random segments, increasing and disjoint, within [0, 100].
std::vector<MajorantSegment> random_segments(std::mt19937& rng, int n) {
    std::uniform_real_distribution<double> u(0.0, 100.0);
    std::vector<double> t(2 * n);
    for (double& x : t) x = u(rng);
    std::sort(t.begin(), t.end());
    std::vector<MajorantSegment> out;
    for (int k = 0; k < n; ++k) out.push_back({t[2 * k], t[2 * k + 1], 0.1 + u(rng)});
    return out;
}

// A slab a < z < b, infinite in x and y, of constant sigma_t.
class Slab final : public CloudDensity {
public:
    Slab(double a, double b, double sigma) : lo_(-1e9, -1e9, a), hi_(1e9, 1e9, b), s_(sigma) {}
    double sigma_t(const glm::dvec3& p) const override { return p.z > lo_.z && p.z < hi_.z ? s_ : 0.0; }
    void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const override {
        out.clear();
        double t0 = 0.0, t1 = t_max;
        if (clip_ray_to_box(ray, lo_, hi_, t0, t1) && t1 > t0) out.push_back({t0, t1, s_});
    }
    double feature_size_m() const override { return 1.0; }

private:
    glm::dvec3 lo_, hi_;
    double s_;
};

}  // namespace

TEST(SceneClouds, AbsentMeansClearSky) {
    const SceneDescription s = SceneDescription::from_json_string(R"({"version": 1})");
    EXPECT_FALSE(s.clouds.has_value());
    EXPECT_FALSE(s.has_clouds());
    EXPECT_EQ(s.cloud_density(), nullptr);
    EXPECT_EQ(s.to_json_string().find("\"clouds\""), std::string::npos);
}

TEST(SceneClouds, JsonReadsEveryKeyAndRoundTrips) {
    const std::string text = scene_with_clouds(R"({
      "layers": [{"bottom_altitude_m": 1200, "top_altitude_m": 2800, "coverage": 0.7, "cloud_type": "altocumulus",
                  "density_per_m": 0.05, "base_scale_m": 5000, "detail_scale_m": 700,
                  "weather_scale_m": 30000, "detail_strength": 0.25, "weather_variation": 0.3,
                  "wind_offset_m": [10, -20], "evolution_m": 250, "seed": 7}],
      "volumes": [{"name": "Cloud", "file": "/abs/cloud.0007.vdb", "grid": "dens",
                   "matrix_world": [[2,0,0,5],[0,2,0,6],[0,0,2,7],[0,0,0,1]],
                   "density_scale": 0.5, "negative": "reject", "placement": "openvdb"}],
      "scattering": {"albedo": 0.99, "g_forward": 0.7, "g_back": -0.2, "w_forward": 0.9},
      "lighting": {"max_steps": 64, "light_steps": 6, "ambient_steps": 2, "light_distance_m": 3000,
                   "multiple_scattering": "octaves", "octaves": 3, "octave_extinction": 0.4, "octave_contribution": 0.6,
                   "octave_eccentricity": 0.7, "min_transmittance": 0.01, "seed": 3,
                   "jitter": false, "max_distance_m": 5e5, "sides": false, "shadow_grid": false},
      "upsampling": {"stride": 4, "finest": 1, "transmittance_tolerance": 0.05, "radiance_tolerance": 0.2,
                     "max_block_size_m": 800}})");
    const SceneDescription s = SceneDescription::from_json_string(text);
    ASSERT_TRUE(s.has_clouds());
    const SceneClouds& c = *s.clouds;
    ASSERT_EQ(c.layers.size(), 1u);
    const CloudLayerParams& l = c.layers[0];
    EXPECT_EQ(l.bottom_altitude_m, 1200);
    EXPECT_EQ(l.top_altitude_m, 2800);
    EXPECT_EQ(l.coverage, 0.7);
    EXPECT_EQ(l.cloud_type, CloudType::altocumulus);
    EXPECT_EQ(l.density_per_m, 0.05);
    EXPECT_EQ(l.base_scale_m, 5000);
    EXPECT_EQ(l.detail_scale_m, 700);
    EXPECT_EQ(l.weather_scale_m, 30000);
    EXPECT_EQ(l.detail_strength, 0.25);
    EXPECT_EQ(l.weather_variation, 0.3);
    EXPECT_EQ(l.wind_offset_m.x, 10);
    EXPECT_EQ(l.wind_offset_m.y, -20);
    EXPECT_EQ(l.evolution_m, 250);
    EXPECT_EQ(l.seed, 7u);
    ASSERT_EQ(c.volumes.size(), 1u);
    const SceneCloudVolume& v = c.volumes[0];
    EXPECT_EQ(v.name, "Cloud");
    EXPECT_EQ(v.file, "/abs/cloud.0007.vdb");
    EXPECT_EQ(v.options.grid, "dens");
    // By rows: row 0 is (2, 0, 0, 5), so the translation (column 3) is (5, 6, 7).
    EXPECT_EQ(v.options.matrix_world[3][0], 5);
    EXPECT_EQ(v.options.matrix_world[3][1], 6);
    EXPECT_EQ(v.options.matrix_world[3][2], 7);
    EXPECT_EQ(v.options.matrix_world[0][0], 2);
    EXPECT_EQ(v.options.density_scale, 0.5);
    EXPECT_EQ(v.options.negative, VdbCloudOptions::Negative::Reject);
    EXPECT_EQ(v.options.placement, VdbCloudOptions::VoxelPlacement::OpenVdb);
    const CloudLightingOptions& o = c.lighting;
    EXPECT_EQ(o.scattering.albedo, 0.99);
    EXPECT_EQ(o.scattering.phase.g_forward, 0.7);
    EXPECT_EQ(o.scattering.phase.g_back, -0.2);
    EXPECT_EQ(o.scattering.phase.w_forward, 0.9);
    EXPECT_EQ(o.max_steps, 64);
    EXPECT_EQ(o.light_steps, 6);
    EXPECT_EQ(o.ambient_steps, 2);
    EXPECT_EQ(o.light_distance_m, 3000);
    EXPECT_EQ(o.multiple_scattering, CloudMultipleScattering::octaves);
    EXPECT_EQ(o.octaves, 3);
    EXPECT_EQ(o.octave_extinction, 0.4);
    EXPECT_EQ(o.octave_contribution, 0.6);
    EXPECT_EQ(o.octave_eccentricity, 0.7);
    EXPECT_EQ(o.min_transmittance, 0.01);
    EXPECT_EQ(o.seed, 3u);
    EXPECT_FALSE(o.jitter);
    EXPECT_EQ(o.max_distance_m, 5e5);
    EXPECT_FALSE(o.sides);
    EXPECT_FALSE(o.shadow_grid);
    const CloudUpsampling& u = c.upsampling;
    EXPECT_EQ(u.stride, 4);
    EXPECT_EQ(u.finest, 1);
    EXPECT_EQ(u.transmittance_tolerance, 0.05);
    EXPECT_EQ(u.radiance_tolerance, 0.2);
    EXPECT_EQ(u.max_block_size_m, 800);
    // The written text reads back to the same text (every value kept exactly).
    const std::string once = s.to_json_string();
    EXPECT_EQ(SceneDescription::from_json_string(once).to_json_string(), once);
}

TEST(SceneClouds, DefaultsAreTheCoresAndAreAllWritten) {
    const SceneDescription s = SceneDescription::from_json_string(
        scene_with_clouds(R"({"layers": [{}], "volumes": [{"file": "/x.vdb"}]})"));
    const CloudLayerParams d;
    const CloudLightingOptions lo;
    const SceneClouds& c = *s.clouds;
    EXPECT_EQ(c.layers[0].coverage, d.coverage);
    // Coverage is the sky seen covered (oktas / 8) unless the scene asks for the area share.
    EXPECT_EQ(c.layers[0].coverage_measure, CloudCoverageMeasure::dome);
    EXPECT_EQ(d.coverage_measure, CloudCoverageMeasure::dome);
    EXPECT_EQ(c.layers[0].density_per_m, d.density_per_m);
    EXPECT_EQ(c.volumes[0].options.grid, "density");
    EXPECT_EQ(c.volumes[0].options.negative, VdbCloudOptions::Negative::Clamp);
    EXPECT_EQ(c.volumes[0].options.placement, VdbCloudOptions::VoxelPlacement::Blender);
    EXPECT_EQ(c.lighting.max_steps, lo.max_steps);
    EXPECT_EQ(c.lighting.multiple_scattering, CloudMultipleScattering::diffusion);
    EXPECT_EQ(c.lighting.scattering.albedo, lo.scattering.albedo);
    EXPECT_EQ(c.upsampling.stride, CloudUpsampling{}.stride);
    EXPECT_EQ(c.upsampling.finest, CloudUpsampling{}.finest);
    const std::string text = s.to_json_string();
    for (const char* key : {"\"bottom_altitude_m\"",
                            "\"wind_offset_m\"",
                            "\"seed\"",
                            "\"name\"",
                            "\"grid\"",
                            "\"matrix_world\"",
                            "\"density_scale\"",
                            "\"negative\"",
                            "\"placement\"",
                            "\"albedo\"",
                            "\"g_forward\"",
                            "\"w_forward\"",
                            "\"max_steps\"",
                            "\"multiple_scattering\"",
                            "\"octave_eccentricity\"",
                            "\"jitter\"",
                            "\"max_distance_m\"",
                            "\"upsampling\"",
                            "\"finest\"",
                            "\"max_block_size_m\""})
        EXPECT_NE(text.find(key), std::string::npos) << key;
}

TEST(SceneClouds, ErrorsNameTheKey) {
    const auto bad = [](const std::string& clouds) {
        return parameter_of([&] { SceneDescription::from_json_string(scene_with_clouds(clouds)); });
    };
    EXPECT_EQ(bad(R"({"layers": [{"coverage": 1.5}]})"), "clouds.layers[0].coverage");
    EXPECT_EQ(bad(R"({"layers": [{}, {"top_altitude_m": 100}]})"), "clouds.layers[1].top_altitude_m");
    EXPECT_EQ(bad(R"({"layers": [{"covrage": 0.5}]})"), "clouds.layers[0].covrage");
    EXPECT_EQ(bad(R"({"layers": [{"seed": -1}]})"), "clouds.layers[0].seed");
    EXPECT_EQ(bad(R"({"layers": [{"wind_offset_m": [1]}]})"), "clouds.layers[0].wind_offset_m");
    EXPECT_EQ(bad(R"({"layers": [{"evolution_m": "soon"}]})"), "clouds.layers[0].evolution_m");
    EXPECT_EQ(bad(R"({"layers": [{"evolution_m": 1e12}]})"), "clouds.layers[0].evolution_m");
    EXPECT_EQ(bad(R"({"layers": {}})"), "clouds.layers");
    EXPECT_EQ(bad(R"({"volumes": [{}]})"), "clouds.volumes[0].file");
    EXPECT_EQ(bad(R"({"volumes": [{"file": ""}]})"), "clouds.volumes[0].file");
    EXPECT_EQ(bad(R"({"volumes": [{"file": "a.vdb", "negative": "abs"}]})"), "clouds.volumes[0].negative");
    EXPECT_EQ(bad(R"({"volumes": [{"file": "a.vdb", "placement": "cycles"}]})"),
              "clouds.volumes[0].placement");
    EXPECT_EQ(bad(R"({"volumes": [{"file": "a.vdb", "density_scale": -1}]})"),
              "clouds.volumes[0].density_scale");
    EXPECT_EQ(bad(R"({"volumes": [{"file": "a.vdb", "matrix_world": [[1,0,0,0]]}]})"),
              "clouds.volumes[0].matrix_world");
    EXPECT_EQ(bad(R"({"volumes": [{"file": "a.vdb", "frame": 3}]})"), "clouds.volumes[0].frame");
    EXPECT_EQ(bad(R"({"scattering": {"albedo": 2}})"), "clouds.scattering.albedo");
    EXPECT_EQ(bad(R"({"scattering": {"g_forward": 1}})"), "clouds.scattering.g_forward");
    EXPECT_EQ(bad(R"({"lighting": {"max_steps": 0}})"), "clouds.lighting.max_steps");
    EXPECT_EQ(bad(R"({"lighting": {"jitter": 1}})"), "clouds.lighting.jitter");
    EXPECT_EQ(bad(R"({"lighting": {"sides": "yes"}})"), "clouds.lighting.sides");
    EXPECT_EQ(bad(R"({"lighting": {"shadow_grid": 1}})"), "clouds.lighting.shadow_grid");
    EXPECT_EQ(bad(R"({"lighting": {"multiple_scattering": "wrenninge"}})"),
              "clouds.lighting.multiple_scattering");
    EXPECT_EQ(bad(R"({"lighting": {"steps": 1}})"), "clouds.lighting.steps");
    EXPECT_EQ(bad(R"({"upsampling": {"stride": 17}})"), "clouds.upsampling.stride");
    EXPECT_EQ(bad(R"({"upsampling": {"finest": 0}})"), "clouds.upsampling.finest");
    EXPECT_EQ(bad(R"({"upsampling": {"radiance_tolerance": -0.1}})"), "clouds.upsampling.radiance_tolerance");
    EXPECT_EQ(bad(R"({"upsampling": {"max_block_size_m": "far"}})"), "clouds.upsampling.max_block_size_m");
    EXPECT_EQ(bad(R"({"upsampling": {"strides": 2}})"), "clouds.upsampling.strides");
    EXPECT_EQ(bad(R"({"layer": []})"), "clouds.layer");
    EXPECT_EQ(bad(R"([])"), "clouds");
    // The message says what is accepted.
    try {
        SceneDescription::from_json_string(scene_with_clouds(R"({"layers": [{"coverage": 1.5}]})"));
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("[0, 1]"), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).find("coverage: coverage"), std::string::npos) << e.what();
    }
}

TEST(SceneClouds, LayersSitOnTheScenesGround) {
    SceneDescription s = SceneDescription::from_json_string(
        R"({"version": 1, "origin_altitude_m": 250, "atmosphere": "mars",
            "clouds": {"layers": [{}]}})");
    const CloudLayerParams p =
        scene_cloud_layer(s.clouds->layers[0], s.atmosphere.bottom_radius_m, s.origin_altitude_m);
    EXPECT_EQ(p.planet_radius_m, s.atmosphere.bottom_radius_m);
    EXPECT_EQ(p.origin_altitude_m, 250.0);
    // The scene's layer and one built by hand with those values are the same density.
    const auto density = s.cloud_density();
    ASSERT_NE(density, nullptr);
    const ProceduralClouds by_hand(p);
    for (double x : {0.0, 1234.0, -5678.0})
        for (double z : {1400.0, 2000.0, 2700.0}) {
            const glm::dvec3 q(x, 0.5 * x, z);
            EXPECT_EQ(density->sigma_t(q), by_hand.sigma_t(q));
        }
}

TEST(SceneClouds, RelativeVdbPathsFollowTheSceneFile) {
    const test::TempDir dir;
    const std::string path = dir.file("shot.json");
    {
        std::ofstream out(path);
        out << scene_with_clouds(
            R"({"volumes": [{"file": "cache/cloud.0001.vdb"}, {"file": "/abs/b.vdb"}]})");
    }
    const SceneDescription s = SceneDescription::from_json_file(path);
    EXPECT_EQ(s.clouds->volumes[0].file, (dir.path / "cache" / "cloud.0001.vdb").string());
    EXPECT_EQ(s.clouds->volumes[1].file, "/abs/b.vdb");
    const SceneDescription t = SceneDescription::from_json_string(
        scene_with_clouds(R"({"volumes": [{"file": "c.vdb"}]})"), "/data/shots");
    EXPECT_EQ(t.clouds->volumes[0].file, "/data/shots/c.vdb");
}

TEST(SceneClouds, BadVolumesNameTheFileKey) {
    const test::TempDir dir;
    const std::string good = dir.file("good.vdb");
    test::write_vdb(good, {test::make_float_grid("density", 10.0, 2, [](int, int, int) { return 1.0f; })});
    const std::string vec = dir.file("vec.vdb");
    {
        auto g = openvdb::Vec3SGrid::create();
        g->setName("density");
        g->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 1, 1));
        test::write_vdb(vec, {g});
    }
    const std::string corrupt = dir.file("corrupt.vdb");
    {
        std::ofstream out(corrupt);
        out << "not a vdb";
    }
    const auto error = [&](const std::string& volume) -> std::string {
        const SceneDescription s = SceneDescription::from_json_string(
            scene_with_clouds(R"({"volumes": [{"file": ")" + good + R"("}, )" + volume + "]}"));
        try {
            s.cloud_density();
        } catch (const InvalidArgument& e) {
            EXPECT_EQ(e.parameter(), "clouds.volumes[1].file") << e.what();
            return e.what();
        }
        ADD_FAILURE() << "no error for " << volume;
        return "";
    };
    const std::string missing = dir.file("missing.vdb");
    EXPECT_NE(error(R"({"file": ")" + missing + R"("})").find(missing), std::string::npos);
    EXPECT_NE(error(R"({"file": ")" + corrupt + R"("})").find(corrupt), std::string::npos);
    const std::string no_grid =
        error(R"({"name": "Smoke", "file": ")" + good + R"(", "grid": "temperature"})");
    EXPECT_NE(no_grid.find("temperature"), std::string::npos);
    EXPECT_NE(no_grid.find("Smoke"), std::string::npos);
    EXPECT_NE(error(R"({"file": ")" + vec + R"("})").find(vec), std::string::npos);
    // The good scene builds: one layer and one volume.
    const SceneDescription ok = SceneDescription::from_json_string(
        scene_with_clouds(R"({"layers": [{}], "volumes": [{"file": ")" + good + R"("}]})"));
    const auto d = ok.cloud_density();
    ASSERT_NE(d, nullptr);
    EXPECT_NE(dynamic_cast<const CloudUnion*>(d.get()), nullptr);
}

TEST(CloudUnion, SigmaIsTheSumOfTheSources) {
    auto a = std::make_shared<HomogeneousBox>(glm::dvec3(0), glm::dvec3(10), 0.3);
    auto b = std::make_shared<HomogeneousBox>(glm::dvec3(5), glm::dvec3(20), 0.05);
    auto c = std::make_shared<Slab>(2.0, 8.0, 0.7);
    const CloudUnion u({a, b, c});
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> x(-5.0, 25.0);
    for (int k = 0; k < 1000; ++k) {
        const glm::dvec3 p(x(rng), x(rng), x(rng));
        EXPECT_DOUBLE_EQ(u.sigma_t(p), a->sigma_t(p) + b->sigma_t(p) + c->sigma_t(p));
    }
    EXPECT_EQ(u.feature_size_m(), 1e-3);
    EXPECT_THROW(CloudUnion({}), InvalidArgument);
    EXPECT_THROW(CloudUnion({a, nullptr}), InvalidArgument);
}

TEST(CloudUnion, MergedSegmentsBoundAndCoverEverySource) {
    std::mt19937 rng(2);
    for (int trial = 0; trial < 200; ++trial) {
        const int K = 1 + int(rng() % 4);
        std::vector<std::vector<MajorantSegment>> lists;
        for (int k = 0; k < K; ++k) lists.push_back(random_segments(rng, int(rng() % 6)));
        if (trial % 7 == 0 && K > 1) lists[1] = lists[0];  // identical end points
        std::vector<MajorantSegment> out;
        merge_majorant_segments(lists, out);
        // Increasing, not overlapping, non-empty pieces.
        for (std::size_t i = 0; i < out.size(); ++i) {
            EXPECT_LT(out[i].t0, out[i].t1);
            if (i > 0) {
                EXPECT_LE(out[i - 1].t1, out[i].t0);
            }
        }
        // At points spread along [0, 100]: inside some input segment iff inside some output
        // piece, and the piece's majorant is at least the sum of the open inputs'.
        for (int q = 0; q <= 4000; ++q) {
            const double t = q * 0.025 + 1e-7;
            double sum = 0.0;
            bool inside = false;
            for (const auto& l : lists)
                for (const auto& s : l)
                    if (t > s.t0 && t < s.t1) {
                        sum += s.majorant;
                        inside = true;
                    }
            const MajorantSegment* piece = nullptr;
            for (const auto& s : out)
                if (t > s.t0 && t < s.t1) piece = &s;
            EXPECT_EQ(inside, piece != nullptr) << "trial " << trial << " t " << t;
            if (piece) {
                EXPECT_GE(piece->majorant, sum * (1.0 - 1e-12));
            }
        }
        // Total covered length equals the length of the union of the inputs.
        std::vector<std::pair<double, double>> all;
        for (const auto& l : lists)
            for (const auto& s : l) all.push_back({s.t0, s.t1});
        std::sort(all.begin(), all.end());
        double union_len = 0.0, hi = -1.0;
        for (auto [a, b] : all) {
            if (a > hi) {
                union_len += b - a;
                hi = b;
            } else if (b > hi) {
                union_len += b - hi;
                hi = b;
            }
        }
        double out_len = 0.0;
        for (const auto& s : out) out_len += s.t1 - s.t0;
        EXPECT_NEAR(out_len, union_len, 1e-9);
    }
}

TEST(CloudUnion, OneSourcePassesThrough) {
    auto a = std::make_shared<HomogeneousBox>(glm::dvec3(0), glm::dvec3(10), 0.3);
    const CloudUnion u({a});
    const CloudRay ray{{-5, 1, 1}, glm::normalize(glm::dvec3(1, 0.1, 0.2))};
    std::vector<MajorantSegment> x, y;
    u.segments(ray, 100.0, x);
    a->segments(ray, 100.0, y);
    ASSERT_EQ(x.size(), y.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
        EXPECT_EQ(x[i].t0, y[i].t0);
        EXPECT_EQ(x[i].t1, y[i].t1);
        EXPECT_EQ(x[i].majorant, y[i].majorant);
    }
}

// Two overlapping constant slabs seen straight up: the march through the union gives the
// transmittance exp(-(s1 (b1 - a1) + s2 (b2 - a2))) of the summed optical depth, and the
// segments are the three pieces with majorants s1, s1 + s2, s2.
TEST(CloudUnion, TwoConstantSlabsClosedForm) {
    const double s1 = 0.02, s2 = 0.01;
    auto a = std::make_shared<Slab>(100.0, 300.0, s1);
    auto b = std::make_shared<Slab>(200.0, 500.0, s2);
    const CloudUnion u({a, b});
    const CloudRay up{{0, 0, 0}, {0, 0, 1}};
    std::vector<MajorantSegment> segs;
    u.segments(up, 1e4, segs);
    ASSERT_EQ(segs.size(), 3u);
    EXPECT_DOUBLE_EQ(segs[0].t0, 100.0);
    EXPECT_DOUBLE_EQ(segs[0].t1, 200.0);
    EXPECT_DOUBLE_EQ(segs[0].majorant, s1);
    EXPECT_DOUBLE_EQ(segs[1].t1, 300.0);
    EXPECT_DOUBLE_EQ(segs[1].majorant, s1 + s2);
    EXPECT_DOUBLE_EQ(segs[2].t1, 500.0);
    EXPECT_DOUBLE_EQ(segs[2].majorant, s2);

    // The fast march's transmittance (exact per step for piecewise-constant media).
    const ConstantIllumination light({0, 0, 1}, {1.0f}, {0.0f});
    CloudLightingOptions o;
    o.min_transmittance = 0.0;
    o.max_steps = 64;
    const std::vector<glm::dvec3> dirs{{0, 0, 1}, glm::normalize(glm::dvec3(1, 0, 1))};
    const CloudResult r = render_clouds(u, light, glm::dvec3(0), dirs, o);
    const double tau = s1 * 200.0 + s2 * 300.0;
    EXPECT_NEAR(r.transmittance[0], std::exp(-tau), 1e-6);
    EXPECT_NEAR(r.transmittance[1], std::exp(-tau * std::sqrt(2.0)), 1e-6);
}
