// Clouds in the equirectangular sky: the image with clouds is the clear sky composited
// under the clouds' own result, pixel by pixel (L = L_sky T + L_cloud), and a layer with
// no coverage leaves the image unchanged bit for bit.
#include <gtest/gtest.h>

#include <cmath>

#include "welkin/cloud_illumination.hpp"
#include "welkin/equirect.hpp"
#include "welkin/procedural_clouds.hpp"
#include "welkin/sky_image.hpp"

using namespace welkin;

TEST(CloudSkyImage, CompositesOverTheClearSky) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    Observer obs;
    obs.sun_direction = glm::normalize(glm::dvec3(0.6, 0.2, 0.5));
    const auto lut = make_sky_method("lut");
    SkyImageOptions clear;
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
    const CloudResult c = render_clouds(*layer, light, glm::dvec3(0.0), dirs, cloudy.cloud_lighting);
    int covered = 0;
    for (std::size_t q = 0; q < dirs.size(); ++q) {
        covered += c.transmittance[q] < 0.99f;
        for (std::size_t ch = 0; ch < 3; ++ch) {
            const double expected = sky.pixels[q * 3 + ch] * c.transmittance[q] + c.radiance[q * 3 + ch];
            EXPECT_NEAR(with.pixels[q * 3 + ch], expected, 1e-5 * std::abs(expected) + 1e-9);
        }
    }
    EXPECT_GT(covered, W * H / 8);  // the layer is visible in the upper half

    p.coverage = 0.0;
    cloudy.clouds = std::make_shared<const ProceduralClouds>(p);
    const SkyImage none = render_equirect_sky(*lut, atm, obs, W, cloudy);
    EXPECT_EQ(none.pixels, sky.pixels);
}
