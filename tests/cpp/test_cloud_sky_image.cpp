// SPDX-License-Identifier: Apache-2.0
// Clouds in the equirectangular sky (sky_image.hpp): the cloudy HDRI is a panoramic
// camera's cloud passes (cloud_passes.hpp: the cloud with the air in front of it)
// composited over the clear HDRI, pixel for pixel; pixels without cloud are the clear
// sky's bit for bit; in an airless atmosphere the image is the plain premultiplied "over"
// L_sky T_c + L_c (the closed form of no air in front); a layer with no coverage leaves the
// image unchanged bit for bit.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cloud_test_util.hpp"
#include "peer_table.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/base/equirect.hpp"
#include "welkin/base/math.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/color/color.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/scene/scene.hpp"

using namespace welkin;
using welkin::test::airless;
using welkin::test::HomogeneousBox;

// The consistency the render engine needs: a full equirectangular panorama at the scene
// origin pointed along +X (Blender's Environment mapping, camera.hpp) sees the same pixel
// directions as the HDRI; its Welkin.Clouds over the clear HDRI,
//     Clouds.rgb + (1 - Clouds.a) L_sky,
// must be the cloudy HDRI. Both march the same cloud rays (same seeds) and get their air
// from the same function, so the two differ by float rounding only (the pixel directions
// are computed two ways, ~1e-16): stated tolerance 1e-4 relative. Hazy air, clouds 8 to
// 40 km away so that the air in front visibly matters (checked: the composite without it
// differs by > 5 % on most cloudy pixels).
TEST(CloudSkyImage, IsThePanoramasCloudPassesOverTheClearSky) {
    const int W = 96, H = 48;
    SceneDescription s;
    s.atmosphere = Atmosphere::preset("hazy");
    s.sun_direction = glm::normalize(glm::dvec3(0.5, 0.4, 0.35));
    Camera cam;
    cam.type = CameraType::Panoramic;
    cam.matrix_world = glm::dmat4(glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 1, 0), glm::dvec4(-1, 0, 0, 0),
                                  glm::dvec4(0, 0, 0, 1));
    s.camera = cam;
    s.resolution = {W, H, 100};
    s.clouds = SceneClouds{};
    CloudLightingOptions& o = s.clouds->lighting;
    o.octaves = 4;
    o.max_steps = 64;
    // A wide deck 8 to 40 km ahead (+X), 1.5 to 2.3 km up: strong haze in front of it.
    const HomogeneousBox box({8e3, -40e3, 1500.0}, {40e3, 40e3, 2300.0}, 0.002);
    const CloudPasses pass = render_cloud_passes(s, box);

    const auto lut = make_sky_method("lut");
    SkyImageOptions clear;
    clear.ground = false;  // the clouds' algebra over the sky alone
    clear.sun_disc = false;
    const SkyImage sky = render_equirect_sky(*lut, s.atmosphere, s.origin_observer(), W, clear);
    SkyImageOptions cloudy = clear;
    cloudy.clouds = std::make_shared<const HomogeneousBox>(box);
    cloudy.cloud_lighting = o;
    cloudy.air_steps = s.aerial.raymarch_steps;
    const SkyImage with = render_equirect_sky(*lut, s.atmosphere, s.origin_observer(), W, cloudy);

    // The cloud's own light without air, for the "air matters" check: the same scene with
    // every cloud at a sky depth (cloud_passes.hpp: no air).
    SceneDescription bare_scene = s;
    bare_scene.aerial.sky_depth_m = 1.0;
    const CloudPasses bare = render_cloud_passes(bare_scene, box);

    int cloudy_pixels = 0, hazed = 0;
    double worst = 0.0;
    for (int q = 0; q < W * H; ++q) {
        const float a = pass.clouds[q * 4 + 3];
        EXPECT_NEAR(with.cloud_transmittance[q], 1.0f - a, 1e-6f);  // alpha = 1 - T_c, rounded
        if (!(a > 0.0f)) {                                          // no cloud: the clear sky, bit for bit
            for (int k = 0; k < 3; ++k) EXPECT_EQ(with.pixels[q * 3 + k], sky.pixels[q * 3 + k]) << q;
            continue;
        }
        cloudy_pixels += a > 0.05f;
        bool differs = false;
        for (int k = 0; k < 3; ++k) {
            const double expected =
                composite_clouds(pass.clouds[q * 4 + k], a, sky.pixels[q * 3 + k], 1.0f, 0.0f);
            const double v = with.pixels[q * 3 + k];
            worst = std::max(worst, std::abs(v - expected) / expected);
            EXPECT_NEAR(v, expected, 1e-4 * expected) << q << " " << k;
            const double no_air =
                composite_clouds(bare.clouds[q * 4 + k], a, sky.pixels[q * 3 + k], 1.0f, 0.0f);
            differs = differs || std::abs(no_air - expected) > 0.05 * expected;
        }
        hazed += a > 0.05f && differs;
    }
    std::printf(
        "cloudy HDRI vs panorama passes over the clear HDRI: max relative difference %.3g "
        "(%d cloudy pixels, %d where the air in front changes a channel > 5 %%)\n",
        worst, cloudy_pixels, hazed);
    ASSERT_GT(cloudy_pixels, 50);  // 102 at 96 x 48
    EXPECT_GT(hazed, cloudy_pixels / 2);
}

// No air: T(0, d_c) = 1 and S(0, d_c) = 0, so the image is L_sky T_c + L_c per wavelength
// (here L_sky = 0: there is no sky either), the composite before the air was applied.
// Spectral output, so that the check is per wavelength; 1e-5 relative (float sums).
TEST(CloudSkyImage, AirlessIsThePlainOver) {
    const Atmosphere atm = airless();
    Observer obs;
    obs.sun_direction = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    const auto lut = make_sky_method("lut");
    SkyImageOptions clear;
    clear.ground = false;  // the clouds' algebra over the sky alone
    clear.sun_disc = false;
    clear.output = SkyImageOptions::Output::Spectral;
    const int W = 64, H = 32;
    const SkyImage sky = render_equirect_sky(*lut, atm, obs, W, clear);

    CloudLayerParams p;
    p.coverage = 0.7;
    p.density_per_m = 0.01;
    auto layer = std::make_shared<const ProceduralClouds>(p);
    SkyImageOptions cloudy = clear;
    cloudy.clouds = layer;
    const SkyImage with = render_equirect_sky(*lut, atm, obs, W, cloudy);

    std::vector<glm::dvec3> dirs;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) dirs.push_back(equirect_pixel_direction(i, j, W, H));
    const AtmosphereIllumination light(atm, obs);
    CloudLightingOptions o = cloudy.cloud_lighting;
    o.ray_spread_rad = kTwoPi / W;  // the image's rays' footprint (sky_image.hpp)
    const CloudResult c = render_clouds(*layer, light, glm::dvec3(0.0), dirs, o);
    const std::size_t nc = atm.channels();
    int covered = 0;
    for (std::size_t q = 0; q < dirs.size(); ++q) {
        covered += c.transmittance[q] < 0.99f;
        for (std::size_t ch = 0; ch < nc; ++ch) {
            const double expected = sky.pixels[q * nc + ch] * c.transmittance[q] + c.radiance[q * nc + ch];
            EXPECT_NEAR(with.pixels[q * nc + ch], expected, 1e-5 * std::abs(expected) + 1e-9);
        }
    }
    EXPECT_GT(covered, W * H / 8);  // the layer is visible in the upper half

    p.coverage = 0.0;
    cloudy.clouds = std::make_shared<const ProceduralClouds>(p);
    const SkyImage none = render_equirect_sky(*lut, atm, obs, W, cloudy);
    EXPECT_EQ(none.pixels, sky.pixels);
}

// With air, a layer with no coverage still leaves the image bit for bit unchanged.
TEST(CloudSkyImage, NoCoverageLeavesTheSkyUnchanged) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    Observer obs;
    obs.sun_direction = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    const auto lut = make_sky_method("lut");
    SkyImageOptions clear;
    clear.ground = false;  // the clouds' algebra over the sky alone
    const SkyImage sky = render_equirect_sky(*lut, atm, obs, 64, clear);
    CloudLayerParams p;
    p.coverage = 0.0;
    SkyImageOptions cloudy = clear;
    cloudy.clouds = std::make_shared<const ProceduralClouds>(p);
    const SkyImage none = render_equirect_sky(*lut, atm, obs, 64, cloudy);
    EXPECT_EQ(none.pixels, sky.pixels);
}

TEST(CloudSkyImage, RejectsBadAirSteps) {
    SkyImageOptions o;
    o.air_steps = 0;
    EXPECT_THROW(o.validate(), InvalidArgument);
}
