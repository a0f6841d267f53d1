// SPDX-License-Identifier: Apache-2.0
// The night sky under clouds (night/moonlit_sky.hpp, stars.hpp, night_glow.hpp): a star,
// the night glow and the moon's disc behind a slab of cloud of known optical depth are
// dimmed by exp(-tau) (Beer-Lambert, the closed form) and unchanged where the sky is clear;
// the clouds lit by the moon alone are the clouds lit by a sun in the moon's direction
// times the irradiance ratio (linearity); while the sun is up, leaving the moon's light on
// the clouds out changes the image by under 1e-3; every value is finite and non-negative.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cloud_test_util.hpp"
#include <gtest/gtest.h>

#include "welkin/astro/moonlight.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/math.hpp"
#include "welkin/night/moonlit_sky.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/night/stars.hpp"
#include "welkin/sky/method.hpp"

namespace welkin {
namespace {

using test::HomogeneousBox;

constexpr double kMeanMoon_m = 384400e3, kAu_m = 149597870.7e3;

glm::dvec3 from_elevation_azimuth(double e_deg, double a_deg) {
    const double e = e_deg * kDegree, a = a_deg * kDegree;
    return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

// A slab of cloud 500 m thick, 1.5 to 2 km up, 4 km wide, over the observer: a ray
// steeper than 45 degrees along its diagonal (53 across its sides) crosses it from base to
// top, h / sin(elevation) long; shallower ones leave it through a side or miss it.
constexpr double kBase = 1500.0, kTop = 2000.0, kHalfWidth = 2000.0, kSigma = 0.004;  // tau 2 at the zenith
std::shared_ptr<const CloudDensity> slab() {
    return std::make_shared<HomogeneousBox>(glm::dvec3(-kHalfWidth, -kHalfWidth, kBase),
                                            glm::dvec3(kHalfWidth, kHalfWidth, kTop), kSigma);
}

// The slab's transmittance along pixel (i, j)'s centre direction, in closed form: 1 for a
// ray that misses it.
double slab_transmittance(int i, int j, int width) {
    const glm::dvec3 d = equirect_to_direction({(i + 0.5) / width, 1.0 - (j + 0.5) / (width / 2)});
    if (!(d.z > 0.0)) return 1.0;
    // Going out from the observer a ray leaves the square's column once, at t_side, never to
    // return: it is in the slab from its base (t0) to its top (t1) or its side.
    const double t0 = kBase / d.z, t1 = kTop / d.z;
    const double t_side = kHalfWidth / std::max(std::abs(d.x), std::abs(d.y));
    if (t_side <= t0) return 1.0;
    return std::exp(-kSigma * (std::min(t1, t_side) - t0));
}

SkyImageOptions cloudy_options() {
    SkyImageOptions options;
    options.clouds = slab();
    options.cloud_upsampling.stride = 1;  // every ray marched: the closed form per pixel
    options.exposure = 3.0;
    return options;
}

void expect_finite_non_negative(const std::vector<float>& pixels, const char* what) {
    for (std::size_t k = 0; k < pixels.size(); ++k) {
        ASSERT_TRUE(std::isfinite(pixels[k])) << what << " value " << k;
        ASSERT_GE(pixels[k], 0.0f) << what << " value " << k;
    }
}

// A star behind the slab (elevation 75 degrees: tau = 2 / sin 75 = 2.07) is dimmed by
// exp(-tau) pixel by pixel, within float rounding of the march's product of its steps'
// exp(-sigma dt); a star 15 degrees up misses the slab and is added unchanged. Same for
// the night glow over the whole image: dimmed behind the slab, unchanged elsewhere.
TEST(NightClouds, StarsAndGlowBehindACloudAreDimmedByBeerLambert) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const auto method = make_sky_method("lut");
    const int width = 128;
    const Observer o = Observer{0.0, from_elevation_azimuth(-40.0, 0.0)}.validated();
    const SkyImageOptions options = cloudy_options();
    const SkyImage base = render_equirect_sky(*method, atm, o, width, options);
    ASSERT_EQ(base.cloud_transmittance.size(), std::size_t(width * width / 2));
    expect_finite_non_negative(base.pixels, "cloudy night sky");

    const std::vector<Star> stars{Star{from_elevation_azimuth(75.0, 40.0), 1.0, 0.6},
                                  Star{from_elevation_azimuth(15.0, -120.0), 1.0, 0.6}};
    SkyImage with_stars = base;
    add_stars(with_stars, atm, o, stars, options);
    SkyImage with_glow = base;
    add_night_glow(with_glow, atm, o, options);
    const std::vector<float> star = star_pixels(atm, o, stars, width, options.output, options.color_space);
    const std::vector<float> glow = night_glow_pixels(atm, o, width, options.output, options.color_space);
    int dimmed = 0, clear = 0;
    double dimmed_energy = 0.0, clear_energy = 0.0;
    for (int j = 0; j < width / 2; ++j)
        for (int i = 0; i < width; ++i) {
            const double t = slab_transmittance(i, j, width);
            for (int c = 0; c < 3; ++c) {
                const std::size_t k = (std::size_t(j) * width + std::size_t(i)) * 3 + std::size_t(c);
                const double added_star = double(with_stars.pixels[k]) - double(base.pixels[k]);
                const double expected_star = options.exposure * t * star[k];
                ASSERT_NEAR(added_star, expected_star, 1e-4 * expected_star + 1e-6 * base.pixels[k] + 1e-30)
                    << "star pixel " << i << ", " << j << " channel " << c << ", T " << t;
                const double added_glow = double(with_glow.pixels[k]) - double(base.pixels[k]);
                const double expected_glow = options.exposure * t * glow[k];
                ASSERT_NEAR(added_glow, expected_glow, 1e-4 * expected_glow + 1e-6 * base.pixels[k] + 1e-30)
                    << "glow pixel " << i << ", " << j << " channel " << c << ", T " << t;
                if (star[k] > 0.0f) {
                    (t < 1.0 ? dimmed_energy : clear_energy) += added_star / (options.exposure * star[k]);
                    ++(t < 1.0 ? dimmed : clear);
                }
            }
        }
    // Both stars were drawn: one behind the slab (each channel of its four pixels dimmed
    // by about exp(-2.07) = 0.126), one in the clear (factor 1).
    ASSERT_GT(dimmed, 0);
    ASSERT_GT(clear, 0);
    EXPECT_NEAR(dimmed_energy / dimmed, std::exp(-kSigma * (kTop - kBase) / std::sin(75.0 * kDegree)), 0.01);
    EXPECT_NEAR(clear_energy / clear, 1.0, 1e-5);
    expect_finite_non_negative(with_stars.pixels, "stars under clouds");
    expect_finite_non_negative(with_glow.pixels, "night glow under clouds");
}

// The moon's disc behind the slab is dimmed by exp(-tau) per pixel, as the sun's is.
TEST(NightClouds, MoonDiscBehindACloudIsDimmedByBeerLambert) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const auto method = make_sky_method("lut");
    const int width = 128;
    const Observer o = Observer{0.0, from_elevation_azimuth(-40.0, 0.0)}.validated();
    Moon moon;
    moon.direction = from_elevation_azimuth(70.0, 100.0);
    moon.sun_from_moon = -moon.direction;  // full
    moon.irradiance_ratio = moon_irradiance_ratio(0.5, kMeanMoon_m, kAu_m);
    const SkyImageOptions options = cloudy_options();
    moon.disc = false;
    const SkyImage without = render_equirect_sky_with_moon(*method, atm, o, moon, width, options);
    moon.disc = true;
    const SkyImage with = render_equirect_sky_with_moon(*method, atm, o, moon, width, options);
    const std::vector<float> disc = moon_disc_pixels(atm, o, moon, width, options.output);
    double sum = 0.0, expected_sum = 0.0;
    for (int j = 0; j < width / 2; ++j)
        for (int i = 0; i < width; ++i)
            for (int c = 0; c < 3; ++c) {
                const std::size_t k = (std::size_t(j) * width + std::size_t(i)) * 3 + std::size_t(c);
                const double expected = options.exposure * slab_transmittance(i, j, width) * disc[k];
                const double added = double(with.pixels[k]) - double(without.pixels[k]);
                ASSERT_NEAR(added, expected, 1e-4 * expected + 1e-6 * without.pixels[k] + 1e-30);
                sum += added;
                expected_sum += options.exposure * disc[k];
            }
    ASSERT_GT(expected_sum, 0.0);
    EXPECT_NEAR(sum / expected_sum, std::exp(-kSigma * (kTop - kBase) / std::sin(70.0 * kDegree)), 0.01);
    expect_finite_non_negative(with.pixels, "moon under clouds");
}

// With the sun far below (no sunlight on the clouds: its direct light is cut by the
// planet, its sky light is the multiple-scattering LUT's, ~0 at 60 degrees down), the
// cloudy moonlit image is the sun's image plus the ratio times the cloudy image of a sun
// in the moon's direction, pixel by pixel within float rounding; and the moon does light
// the clouds: their pixels are brighter than the moonlit sky seen through them.
TEST(NightClouds, CloudsLitByTheMoonAreTheScaledSunlitClouds) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const auto method = make_sky_method("lut");
    const int width = 128;
    Observer o;
    o.sun_direction = from_elevation_azimuth(-60.0, 0.0);
    Moon moon;
    moon.direction = from_elevation_azimuth(35.0, 150.0);
    moon.sun_from_moon = -moon.direction;
    moon.irradiance_ratio = moon_irradiance_ratio(10.0, kMeanMoon_m, kAu_m);
    moon.disc = false;
    SkyImageOptions options = cloudy_options();
    options.sun_disc = false;
    options.cloud_upsampling = CloudUpsampling{};  // the default upsampling: the same for both lights
    ASSERT_FALSE(moon_clouds_left_out(o));
    const SkyImage night = render_equirect_sky_with_moon(*method, atm, o, moon, width, options);
    const SkyImage dark = render_equirect_sky(*method, atm, o, width, options);
    Observer mo = o;
    mo.sun_direction = moon.direction;
    const SkyImage lit = render_equirect_sky(*method, atm, mo, width, options);
    SkyImageOptions clear = options;
    clear.clouds = nullptr;
    const SkyImage lit_clear = render_equirect_sky(*method, atm, mo, width, clear);
    double max_rel = 0.0, cloud_gain = 0.0;
    int cloudy = 0;
    for (std::size_t p = 0; p < night.cloud_transmittance.size(); ++p)
        for (std::size_t c = 0; c < 3; ++c) {
            const std::size_t k = p * 3 + c;
            const double expected = dark.pixels[k] + moon.irradiance_ratio * lit.pixels[k];
            max_rel =
                std::max(max_rel, std::abs(night.pixels[k] - expected) / std::max(1e-30, std::abs(expected)));
            const float t = night.cloud_transmittance[p];
            if (t < 0.5f) {
                // The cloud's own (moon) light over the moonlit sky dimmed by the cloud.
                cloud_gain +=
                    night.pixels[k] - dark.pixels[k] - moon.irradiance_ratio * t * lit_clear.pixels[k];
                ++cloudy;
            }
        }
    std::printf("moonlit clouds against the scaled sunlit clouds: max relative difference %.3g\n", max_rel);
    EXPECT_LT(max_rel, 1e-5);
    ASSERT_GT(cloudy, 0);
    EXPECT_GT(cloud_gain / cloudy, 0.0);
    expect_finite_non_negative(night.pixels, "moonlit clouds");
}

// While the sun is up the moon's light on the clouds is left out (moon_clouds_left_out):
// against the image that marches the clouds for both lights, the difference is under
// 1e-3 of every pixel, with the sun just up (0.5 degrees: its light on the clouds at its
// weakest) and the brightest moon high above.
TEST(NightClouds, MoonlightOnCloudsLeftOutWhileTheSunIsUpIsNegligible) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const auto method = make_sky_method("lut");
    const int width = 64;
    Observer o;
    o.sun_direction = from_elevation_azimuth(0.5, 0.0);
    ASSERT_TRUE(moon_clouds_left_out(o));
    Moon moon;
    moon.direction = from_elevation_azimuth(60.0, 180.0);
    moon.sun_from_moon = -moon.direction;
    moon.irradiance_ratio = moon_irradiance_ratio(0.0, 356400e3, kAu_m);  // full, at perigee
    moon.disc = false;
    SkyImageOptions options = cloudy_options();
    options.sun_disc = false;
    const SkyImage fast = render_equirect_sky_with_moon(*method, atm, o, moon, width, options);
    const SkyImage sun = render_equirect_sky(*method, atm, o, width, options);
    Observer mo = o;
    mo.sun_direction = moon.direction;
    const SkyImage lit = render_equirect_sky(*method, atm, mo, width, options);
    double worst = 0.0;
    for (std::size_t k = 0; k < fast.pixels.size(); ++k) {
        const double full = sun.pixels[k] + moon.irradiance_ratio * lit.pixels[k];
        worst = std::max(worst, std::abs(fast.pixels[k] - full) / std::max(1e-30, full));
    }
    std::printf("moon's light on the clouds left out, sun 0.5 deg up: at most %.3g of a pixel\n", worst);
    EXPECT_LT(worst, 1e-3);
    expect_finite_non_negative(fast.pixels, "sunlit clouds with a moon");
}

}  // namespace
}  // namespace welkin
