// SPDX-License-Identifier: Apache-2.0
// The march's view cache (clouds/lighting.hpp, CloudViewCache): rays lit again from their
// kept samples give what a march gives, bit for bit, under another sun; a cache kept under
// another key is emptied; one too small keeps what fits and marches the rest.
#include <memory>
#include <numbers>
#include <vector>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/procedural.hpp"

using namespace welkin;
using welkin::test::sky_grid;

namespace {

ConstantIllumination sun_at(const glm::dvec3& s) {
    return ConstantIllumination(glm::normalize(s), {1.0f, 0.9f, 0.8f}, {0.1f, 0.15f, 0.25f},
                                {0.05f, 0.05f, 0.04f});
}

CloudLightingOptions pixel_options(int W) {
    CloudLightingOptions o;
    o.max_steps = 48;
    o.ray_spread_rad = 2.0 * std::numbers::pi / W;
    return o;
}

void expect_same(const CloudResult& a, const CloudResult& b) {
    EXPECT_EQ(a.radiance, b.radiance);
    EXPECT_EQ(a.transmittance, b.transmittance);
    EXPECT_EQ(a.depth_m, b.depth_m);
    EXPECT_EQ(a.interpolation.marched, b.interpolation.marched);
}

}  // namespace

// A sky marched under one sun, then lit again under another from the kept samples: the same
// as a march under the second sun alone, upsampled (the refined rays differ between the two
// suns: those not kept are marched and kept) and not; the cache reports the rays it served.
TEST(CloudViewCache, LightingAgainIsTheMarch) {
    const int W = 96, H = 32;
    const ProceduralClouds layer(CloudLayerParams::preset(CloudType::altocumulus));
    const auto dirs = sky_grid(W, H);
    const auto first = sun_at({0.6, 0.2, 0.5}), second = sun_at({-0.3, 0.7, 0.15});
    CloudUpsampling up;
    up.stride = 8, up.finest = 2;
    for (const bool grid : {true, false}) {
        const auto render = [&](const ConstantIllumination& l, const CloudLightingOptions& o) {
            return grid ? render_clouds_grid(layer, l, glm::dvec3(0.0), dirs, W, o, up, nullptr, 7)
                        : render_clouds(layer, l, glm::dvec3(0.0), dirs, o);
        };
        CloudLightingOptions cached = pixel_options(W);
        cached.view_cache = std::make_shared<CloudViewCache>();
        EXPECT_FALSE(cached.view_cache->keep("sky"));
        const CloudResult a = render(first, cached);
        expect_same(a, render(first, pixel_options(W)));
        const std::size_t kept = cached.view_cache->rays();
        EXPECT_GT(kept, dirs.size() / 8) << grid;
        EXPECT_EQ(cached.view_cache->reused(), 0u);

        EXPECT_TRUE(cached.view_cache->keep("sky"));
        const CloudResult b = render(second, cached);
        const CloudResult marched = render(second, pixel_options(W));
        expect_same(b, marched);
        EXPECT_NE(a.radiance, b.radiance);  // the light did change
        std::size_t cloudy = 0;
        for (const float t : marched.transmittance) cloudy += t < 0.99f;
        EXPECT_GT(cloudy, dirs.size() / 20) << grid;
        // Every ray the first render marched and the second marched again came from the cache.
        std::size_t both = 0;
        for (std::size_t q = 0; q < dirs.size(); ++q)
            both += a.interpolation.was_marched(q) && b.interpolation.was_marched(q);
        EXPECT_EQ(cached.view_cache->reused(), both) << grid;
        EXPECT_GE(cached.view_cache->rays(), kept);
    }
}

// Another key empties the cache; the same key keeps it.
TEST(CloudViewCache, AnotherKeyEmptiesIt) {
    const int W = 32, H = 8;
    const ProceduralClouds layer(CloudLayerParams::preset(CloudType::cumulus));
    const auto dirs = sky_grid(W, H);
    CloudLightingOptions o = pixel_options(W);
    o.view_cache = std::make_shared<CloudViewCache>();
    o.view_cache->keep("a");
    render_clouds(layer, sun_at({0.6, 0.2, 0.5}), glm::dvec3(0.0), dirs, o);
    EXPECT_EQ(o.view_cache->rays(), dirs.size());
    EXPECT_GT(o.view_cache->bytes(), 0u);
    EXPECT_TRUE(o.view_cache->keep("a"));
    EXPECT_EQ(o.view_cache->rays(), dirs.size());
    EXPECT_FALSE(o.view_cache->keep("b"));
    EXPECT_EQ(o.view_cache->rays(), 0u);
    EXPECT_EQ(o.view_cache->bytes(), 0u);
}

// A cache too small for every ray keeps what fits, within its bound, and the rays it does not
// hold are marched: the result is still the march's.
TEST(CloudViewCache, ABoundedCacheKeepsWhatFits) {
    const int W = 64, H = 16;
    const ProceduralClouds layer(CloudLayerParams::preset(CloudType::stratocumulus));
    const auto dirs = sky_grid(W, H);
    CloudLightingOptions o = pixel_options(W);
    o.view_cache = std::make_shared<CloudViewCache>(16 << 10);
    o.view_cache->keep("small");
    const auto first = sun_at({0.6, 0.2, 0.5}), second = sun_at({0.1, -0.8, 0.3});
    render_clouds(layer, first, glm::dvec3(0.0), dirs, o);
    EXPECT_GT(o.view_cache->rays(), 0u);
    EXPECT_LT(o.view_cache->rays(), dirs.size());
    EXPECT_LE(o.view_cache->bytes(), std::size_t(16 << 10));
    const CloudResult again = render_clouds(layer, second, glm::dvec3(0.0), dirs, o);
    expect_same(again, render_clouds(layer, second, glm::dvec3(0.0), dirs, pixel_options(W)));
}

// The sky's weights a sample keeps are those of its kind of sky: kept under a sky of one
// radiance all round and lit again under two skies (and the other way round), a ray's
// samples are lit with the new kind's weights, as a march under it alone.
TEST(CloudViewCache, AnotherKindOfSkyIsLitAfresh) {
    const int W = 48, H = 16;
    const ProceduralClouds layer(CloudLayerParams::preset(CloudType::stratocumulus));
    const auto dirs = sky_grid(W, H);
    const glm::dvec3 s = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    const ConstantIllumination one(s, {1.0f, 0.9f, 0.8f}, {0.1f, 0.15f, 0.25f});
    const ConstantIllumination two = sun_at({0.6, 0.2, 0.5});
    ASSERT_TRUE(one.uniform_sky());
    ASSERT_FALSE(two.uniform_sky());
    for (const bool one_first : {true, false}) {
        const ConstantIllumination& a = one_first ? one : two;
        const ConstantIllumination& b = one_first ? two : one;
        CloudLightingOptions o = pixel_options(W);
        o.view_cache = std::make_shared<CloudViewCache>();
        o.view_cache->keep("sky");
        render_clouds(layer, a, glm::dvec3(0.0), dirs, o);
        o.view_cache->keep("sky");
        const CloudResult again = render_clouds(layer, b, glm::dvec3(0.0), dirs, o);
        EXPECT_EQ(o.view_cache->reused(), dirs.size()) << one_first;
        expect_same(again, render_clouds(layer, b, glm::dvec3(0.0), dirs, pixel_options(W)));
    }
}
