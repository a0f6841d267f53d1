// SPDX-License-Identifier: Apache-2.0
// The rules by which method="auto" chooses (include/welkin/sky/auto.hpp), on small
// synthetic tables whose answer is known: cheapest that meets the tolerance, the cost
// depending on the number of directions; the worst grid corner around an off-grid scene;
// a setting that failed (non-finite) at a corner is never chosen there; no setting
// meeting the tolerance falls back to the most accurate and says so; an atmosphere that is
// not exactly a charted preset is judged by the worst preset. The generated table itself
// is exercised end to end against the reference in tests/python/test_auto.py.
#include <cmath>
#include <string>
#include <vector>

#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/sky/auto.hpp"

namespace welkin {
namespace {

using auto_table::kInf;
using auto_table::Setting;
using auto_table::Table;

constexpr double kAlts[] = {0.0, 1000.0};
constexpr double kSuns[] = {0.0, 10.0};
constexpr const char* kPresets[] = {"bruneton2017", "hazy"};
// lut: a fixed cost (LUT builds), nothing per direction; raymarch: the opposite.
constexpr Setting kSettings[] = {
    {"lut", false, 256, 64, 32, 192, 108, 64, 32, 0.01, 0.0},
    {"raymarch", false, 256, 64, 32, 192, 108, 16, 8, 0.0, 1e-5},
    {"analytic", false, 256, 64, 32, 192, 108, 64, 32, 0.0, 1e-9},
};

struct SyntheticTable {
    // [preset][setting][alt][sun]; every setting meets 0.1 everywhere but analytic.
    std::vector<double> p95 = std::vector<double>(2 * 3 * 2 * 2, 0.05);
    std::vector<double> noise = std::vector<double>(2 * 2 * 2, 0.0);  // [preset][alt][sun]
    double& at(int preset, int setting, int alt, int sun) {
        return p95[((preset * 3 + setting) * 2 + alt) * 2 + sun];
    }
    SyntheticTable() {
        for (int p = 0; p < 2; ++p)
            for (int a = 0; a < 2; ++a)
                for (int s = 0; s < 2; ++s) at(p, 2, a, s) = 0.5;
    }
    Table table() const {
        return Table{kAlts, kSuns, kPresets, kSettings, p95.data(), noise.data(), 1024, 1e-6};
    }
};

Observer scene(double altitude_m, double sun_elevation_deg) {
    const double e = sun_elevation_deg * kDegree;
    return Observer{altitude_m, {0.0, std::cos(e), std::sin(e)}};
}

const Atmosphere& earth() {
    static const Atmosphere a = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    return a;
}

TEST(AutoSky, CheapestThatMeetsDependsOnTheNumberOfDirections) {
    const SyntheticTable t;
    // 10 directions: raymarch costs 1e-4 s, lut 0.01 s. An HDRI: raymarch 21 s, lut 0.01 s.
    const AutoChoice few = choose_sky_method(earth(), scene(0, 0), 10, 0.1, {}, t.table());
    EXPECT_EQ(few.method, "raymarch");
    EXPECT_EQ(few.options.raymarch_steps, 16);
    EXPECT_TRUE(few.meets_tolerance);
    const AutoChoice many = choose_sky_method(earth(), scene(0, 0), 2048 * 1024, 0.1, {}, t.table());
    EXPECT_EQ(many.method, "lut");
    EXPECT_DOUBLE_EQ(many.predicted_seconds, 0.01);
    // A loose tolerance lets the analytic method in: the cheapest of all.
    EXPECT_EQ(choose_sky_method(earth(), scene(0, 0), 2048 * 1024, 0.6, {}, t.table()).method, "analytic");
}

TEST(AutoSky, OffGridSceneIsJudgedByItsWorstCorner) {
    SyntheticTable t;
    t.at(0, 0, 1, 1) = 0.2;  // lut misses 0.1 at (1 km, 10 deg) only
    // Inside the cell: that corner counts, so lut is out.
    const AutoChoice inside = choose_sky_method(earth(), scene(500, 5), 2048 * 1024, 0.1, {}, t.table());
    EXPECT_EQ(inside.method, "raymarch");
    // On the grid point (0 m, 0 deg) only that point counts.
    EXPECT_EQ(choose_sky_method(earth(), scene(0, 0), 2048 * 1024, 0.1, {}, t.table()).method, "lut");
    // Beyond the grid: the nearest edge (1 km, 10 deg) counts.
    EXPECT_EQ(choose_sky_method(earth(), scene(4e5, 60), 2048 * 1024, 0.1, {}, t.table()).method, "raymarch");
}

TEST(AutoSky, NeverChoosesASettingThatFailedNearTheScene) {
    SyntheticTable t;
    t.at(0, 0, 0, 1) = kInf;  // lut gave a non-finite value at (0 m, 10 deg)
    const AutoChoice c = choose_sky_method(earth(), scene(0, 5), 2048 * 1024, 10.0, {}, t.table());
    EXPECT_NE(c.method, "lut");
    // Even when nothing meets the tolerance, the fallback is a finite one.
    const AutoChoice strict = choose_sky_method(earth(), scene(0, 5), 2048 * 1024, 0.001, {}, t.table());
    EXPECT_NE(strict.method, "lut");
}

TEST(AutoSky, FallsBackToTheMostAccurateAndSaysSo) {
    SyntheticTable t;
    t.at(0, 1, 0, 0) = 0.03;  // raymarch is the most accurate at (0 m, 0 deg)
    const AutoChoice c = choose_sky_method(earth(), scene(0, 0), 2048 * 1024, 0.01, {}, t.table());
    EXPECT_FALSE(c.meets_tolerance);
    EXPECT_EQ(c.method, "raymarch");
    EXPECT_DOUBLE_EQ(c.predicted_error, 0.03);
}

TEST(AutoSky, FallbackTakesTheCheapestWithinTheReferenceNoiseOfTheBest) {
    SyntheticTable t;
    t.at(0, 1, 0, 0) = 0.03;  // raymarch: 0.03; lut: 0.05, but the chart's truth is +-0.03
    t.noise[0] = 0.03;        // bruneton2017, 0 m, 0 deg
    const AutoChoice c = choose_sky_method(earth(), scene(0, 0), 2048 * 1024, 0.01, {}, t.table());
    EXPECT_FALSE(c.meets_tolerance);
    EXPECT_EQ(c.method, "lut");  // 0.01 s rather than 21 s, indistinguishable error
}

TEST(AutoSky, AtmosphereNotAChartedPresetIsJudgedByTheWorstPreset) {
    SyntheticTable t;
    t.at(1, 0, 0, 0) = 0.3;  // lut misses 0.1 for "hazy" only
    EXPECT_EQ(choose_sky_method(earth(), scene(0, 0), 2048 * 1024, 0.1, {}, t.table()).method, "lut");
    Atmosphere other = earth();
    other.mie_g = 0.5;  // still named bruneton2017, but not it
    EXPECT_EQ(choose_sky_method(other, scene(0, 0), 2048 * 1024, 0.1, {}, t.table()).method, "raymarch");
}

// The generated table: the default atmosphere (four wavelengths, one SIMD batch) is judged
// by the chart's default rows, a 48-wavelength one by its spectral rows; an HDRI of the
// default sky by day gets a default-wavelength LUT, not a spectral setting (which costs ten
// times as much).
TEST(AutoSky, DefaultWavelengthsTakeTheDefaultRows) {
    const Atmosphere fast = Atmosphere::preset("bruneton2017");
    ASSERT_EQ(fast.channels(), 4u);
    const AutoChoice day = choose_sky_method(fast, scene(0, 30), 2048 * 1024, 0.05);
    EXPECT_EQ(day.setting.find("spectral"), std::string::npos) << day.setting;
    EXPECT_EQ(day.method, "lut") << day.setting;
    const Atmosphere spectral = Atmosphere::preset("bruneton2017", spectral_wavelengths_nm());
    const AutoChoice exact = choose_sky_method(spectral, scene(0, 30), 2048 * 1024, 0.05);
    EXPECT_NE(exact.setting.find("spectral"), std::string::npos) << exact.setting;
    EXPECT_GT(exact.predicted_seconds, 5.0 * day.predicted_seconds);
}

TEST(AutoSky, BadToleranceNamesTheParameterAndRange) {
    for (double bad : {0.0, -1.0, 1e-4, 11.0, std::nan(""), kInf}) {
        try {
            choose_sky_method(earth(), scene(0, 0), 10, bad);
            ADD_FAILURE() << "accepted tolerance " << bad;
        } catch (const InvalidArgument& e) {
            EXPECT_NE(std::string(e.what()).find("tolerance"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("[0.001, 10]"), std::string::npos) << e.what();
        }
        SkyOptions o;
        o.tolerance = bad;
        EXPECT_THROW(make_sky_method("auto", o), InvalidArgument);
    }
}

}  // namespace
}  // namespace welkin
