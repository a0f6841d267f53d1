// SPDX-License-Identifier: Apache-2.0
// The lut method's cache of atmosphere LUTs (lut_cache.hpp): a sun change reuses the
// tables, any change of the atmosphere or of the LUT sizes rebuilds them, cached results
// are identical to fresh ones, and concurrent callers get correct tables. Also: the lut
// method's output does not depend on the number of threads.
#include <cmath>
#include <thread>
#include <vector>

#include "peer_table.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "welkin/atmosphere/lut_cache.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/sky/lut.hpp"

using namespace welkin;

namespace {

std::vector<glm::dvec3> some_directions() {
    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 32; ++i) dirs.push_back(equirect_pixel_direction(i, j, 32, 16));
    return dirs;
}

Observer sun(double elevation, double azimuth, double altitude_m = 0.0) {
    return Observer{altitude_m, glm::dvec3(std::cos(elevation) * std::cos(azimuth),
                                           std::cos(elevation) * std::sin(azimuth), std::sin(elevation))};
}

std::vector<float> render(const LutSky& sky, const Atmosphere& atm, const Observer& obs) {
    const std::vector<glm::dvec3> dirs = some_directions();
    std::vector<float> out(dirs.size() * atm.channels());
    sky.radiance(atm, obs, dirs, out);
    return out;
}

}  // namespace

TEST(LutCache, SunChangeReusesTheTablesAndMatchesAFreshBuildExactly) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    AtmosphereLutCache cache;
    const LutSky cached({}, &cache), fresh({}, nullptr);
    for (const Observer& obs : {sun(0.5, 0.3), sun(0.05, 2.0), sun(-0.02, 1.0), sun(1.2, -0.7, 1500.0)})
        EXPECT_EQ(render(cached, atm, obs), render(fresh, atm, obs));
    EXPECT_EQ(cache.builds(), 1u);
}

TEST(LutCache, AnyChangeOfTheAtmosphereOrOfTheLutSizesRebuilds) {
    const Atmosphere base = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    std::vector<Atmosphere> changed(6, base);
    changed[0].mie_g = std::nextafter(base.mie_g, 1.0);  // one ulp
    changed[1].ground_albedo[2] = 0.3;
    changed[2].rayleigh_scattering[0] *= 1.0 + 1e-15;
    changed[3].sun_angular_radius_rad *= 2.0;
    changed[4].absorption_density = DensityProfile::tent(12e3, 25e3, 40e3);
    changed[5].mie_phase = MiePhaseModel::HenyeyGreenstein;
    AtmosphereLutCache cache(1);
    const Observer obs = sun(0.3, 0.0);
    const LutSky cached({}, &cache), fresh({}, nullptr);
    render(cached, base, obs);
    std::size_t builds = 1;
    for (const Atmosphere& atm : changed) {
        EXPECT_EQ(render(cached, atm, obs), render(fresh, atm, obs));
        EXPECT_EQ(cache.builds(), ++builds);
        render(cached, atm, obs);  // the same one again: no rebuild
        EXPECT_EQ(cache.builds(), builds);
    }
    SkyOptions bigger;
    bigger.multiscattering_size = 48;
    const LutSky other_sizes(bigger, &cache);
    render(other_sizes, base, obs);
    EXPECT_EQ(cache.builds(), ++builds);
    bigger.skyview_width = 96;  // the sky-view LUT is built per call: not part of the key
    render(LutSky(bigger, &cache), base, obs);
    EXPECT_EQ(cache.builds(), builds);
}

TEST(LutCache, KeepsTheMostRecentlyUsedEntries) {
    const Atmosphere a = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm),
                     b = Atmosphere::preset("hazy"), c = Atmosphere::preset("mars");
    AtmosphereLutCache cache(2);
    const LutResolution o;
    const auto la = cache.get(a, o);
    cache.get(b, o);
    EXPECT_EQ(cache.get(a, o), la);  // a is now the most recent, b the least
    cache.get(c, o);                 // evicts b
    EXPECT_EQ(cache.builds(), 3u);
    EXPECT_EQ(cache.get(a, o), la);
    cache.get(b, o);
    EXPECT_EQ(cache.builds(), 4u);
    cache.clear();
    EXPECT_NE(cache.get(a, o), la);  // rebuilt; the old tables stay valid while held
    EXPECT_EQ(la->channels(), 3u);
}

TEST(LutCache, ConcurrentCallersGetTheRightTables) {
    const Atmosphere a = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm),
                     b = Atmosphere::preset("polluted");
    AtmosphereLutCache cache(1);  // the two atmospheres keep evicting each other
    const LutSky cached({}, &cache), fresh({}, nullptr);
    const Observer obs = sun(0.4, 1.0);
    const std::vector<float> want_a = render(fresh, a, obs), want_b = render(fresh, b, obs);
    std::vector<std::thread> threads;
    std::vector<int> ok(8, 0);
    for (int t = 0; t < 8; ++t)
        threads.emplace_back([&, t] {
            bool good = true;
            for (int k = 0; k < 3; ++k) {
                const bool use_a = (t + k) % 2 == 0;
                good = good && render(cached, use_a ? a : b, obs) == (use_a ? want_a : want_b);
            }
            ok[std::size_t(t)] = good;
        });
    for (std::thread& th : threads) th.join();
    for (int t = 0; t < 8; ++t) EXPECT_TRUE(ok[std::size_t(t)]) << "thread " << t;
}

TEST(LutThreads, OutputDoesNotDependOnTheThreadCount) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const LutSky sky({}, nullptr);
    const Observer obs = sun(0.2, 0.5, 0.5);
    const std::vector<float> many = render(sky, atm, obs);
    const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_EQ(render(sky, atm, obs), many);
}
