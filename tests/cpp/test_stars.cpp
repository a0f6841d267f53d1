// SPDX-License-Identifier: Apache-2.0
// The stars (night/stars.hpp): the compiled-in catalogue, a star's light at the top of the
// atmosphere against its V and colour, and its energy in the image against its irradiance
// through the air at any resolution.
#include <algorithm>
#include <cmath>

#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/math.hpp"
#include "welkin/night/stars.hpp"

namespace welkin {
namespace {

using test::parameter_of;

glm::dvec3 from_elevation_azimuth(double e_deg, double a_deg) {
    const double e = e_deg * kDegree, a = a_deg * kDegree;
    return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

std::vector<double> energy_of(const std::vector<float>& px, int width, std::size_t nc) {
    const int height = width / 2;
    std::vector<double> energy(nc, 0.0);
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i)
            for (std::size_t c = 0; c < nc; ++c) {
                const double v = px[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * nc + c];
                EXPECT_TRUE(std::isfinite(v) && v >= 0.0);
                energy[c] += v * equirect_pixel_solid_angle(j, width, height);
            }
    return energy;
}

TEST(Stars, CatalogueIsHipparcosBrightestFirst) {
    const auto stars = hipparcos_stars();
    ASSERT_GT(stars.size(), 15000u);
    EXPECT_TRUE(
        std::is_sorted(stars.begin(), stars.end(),
                       [](const CatalogueStar& a, const CatalogueStar& b) { return a.v_mag < b.v_mag; }));
    EXPECT_LE(stars.back().v_mag, 7.0);
    // Vega (HIP 91262): V 0.03, B-V 0.00 (Johnson 1966); its Hipparcos position.
    const auto vega = std::find_if(stars.begin(), stars.end(), [](const CatalogueStar& s) {
        return std::abs(s.ra_deg - 279.2341) < 1e-3 && std::abs(s.dec_deg - 38.7830) < 1e-3;
    });
    ASSERT_NE(vega, stars.end());
    EXPECT_NEAR(vega->v_mag, 0.03, 0.05);
    EXPECT_NEAR(vega->b_v, 0.0, 0.01);
}

TEST(Stars, ColourTemperatureAndIrradiance) {
    // Ballesteros 2012 checks his formula on the sun: B-V 0.65 -> about 5780 K.
    EXPECT_NEAR(star_temperature_k(0.65), 5778.0, 60.0);
    EXPECT_GT(star_temperature_k(-0.3), star_temperature_k(0.0));
    EXPECT_GT(star_temperature_k(0.0), star_temperature_k(1.5));
    // At 545 nm the irradiance is V's: 3.631e-11 W m^-2 nm^-1 x 10^(-0.4 V).
    const std::vector<double> wl{450.0, 545.0, 650.0};
    for (double bv : {-0.2, 0.0, 0.65, 1.6}) {
        const std::vector<double> e = star_irradiance(1.5, bv, wl);
        EXPECT_NEAR(e[1] / (3.631e-11 * std::pow(10.0, -0.6)), 1.0, 1e-12);
        // Blue stars are brighter in blue than in red, red ones the other way.
        if (bv < 0.0) {
            EXPECT_GT(e[0], e[2]);
        }
        if (bv > 1.0) {
            EXPECT_LT(e[0], e[2]);
        }
    }
    EXPECT_EQ(parameter_of([&] { star_irradiance(NAN, 0.0, wl); }), "v_mag");
}

TEST(Stars, EnergyInTheImageIsTheIrradianceThroughTheAir) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const std::size_t nc = atm.channels();
    const Observer o = Observer{0.0, {0.0, 0.0, 1.0}}.validated();
    // Stars at several elevations and azimuths, one on the image's seam (azimuth 180: u = 0).
    for (const auto& [e_deg, a_deg] : {std::pair{40.0, 30.0}, {5.0, 180.0}, {89.9, 200.0}, {0.7, -75.0}}) {
        const Star star{from_elevation_azimuth(e_deg, a_deg), 2.0, 0.4};
        const std::vector<double> top = star_irradiance(2.0, 0.4, atm.wavelengths_nm);
        const std::vector<double> t = transmittance_to_boundary(atm, atm.bottom_radius_m, star.direction.z);
        for (int width : {16, 256, 2048}) {
            const std::vector<Star> one{star};
            const std::vector<double> energy =
                energy_of(star_pixels(atm, o, one, width, SkyImageOptions::Output::Spectral), width, nc);
            for (std::size_t c = 0; c < nc; ++c)
                EXPECT_NEAR(energy[c] / (top[c] * t[c]), 1.0, 2e-3)
                    << "elevation " << e_deg << " width " << width;
        }
    }
    // Behind the ground: nothing.
    const std::vector<Star> below{Star{from_elevation_azimuth(-2.0, 10.0), -1.0, 0.0}};
    for (double v : star_pixels(atm, o, below, 64, SkyImageOptions::Output::Rgb)) EXPECT_EQ(v, 0.0f);
}

TEST(Stars, SameEnergyAtEveryResolution) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const Observer o = Observer{0.0, {0.0, 0.0, 1.0}}.validated();
    const std::vector<Star> one{Star{from_elevation_azimuth(23.0, 117.0), 0.5, 1.2}};
    std::vector<double> first;
    for (int width : {16, 256, 2048}) {
        const std::vector<double> e =
            energy_of(star_pixels(atm, o, one, width, SkyImageOptions::Output::Rgb), width, 3);
        if (first.empty()) first = e;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[std::size_t(c)] / first[std::size_t(c)], 1.0, 1e-6);
    }
}

TEST(Stars, BadInput) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
    const std::vector<Star> bad{Star{{0.0, 0.0, 0.0}, 1.0, 0.0}};
    EXPECT_EQ(parameter_of([&] { star_pixels(atm, Observer{}, bad, 16, SkyImageOptions::Output::Rgb); }),
              "stars.direction");
    EXPECT_EQ(parameter_of([&] { star_pixels(atm, Observer{}, {}, 15, SkyImageOptions::Output::Rgb); }),
              "width");
    EXPECT_EQ(parameter_of([&] { stars_at(Instant{}, Place{}, 99.0); }), "faintest_v");
}

}  // namespace
}  // namespace welkin
