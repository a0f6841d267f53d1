// SPDX-License-Identifier: Apache-2.0
// Equirect sky images: layout, the single method call, colour conversion, the sun disc's
// energy and shape, exposure, no NaN, cancellation, bad input.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "peer_table.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/atmosphere/sun.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"
#include "welkin/render/sky_image.hpp"

using namespace welkin;

namespace {

// Test doubles for SkyMethod: radiance = f(direction, channel).
class FakeSky final : public SkyMethod {
public:
    enum Kind { Zero, Constant, Zenith, NaNAtOne, Cancelling };
    explicit FakeSky(Kind kind) : kind_(kind) {}
    std::string name() const override { return "fake"; }
    void radiance(const Atmosphere& atm, const Observer&, std::span<const glm::dvec3> dirs,
                  std::span<float> out, std::span<float>, Progress* progress) const override {
        ++calls;
        last_count = dirs.size();
        first_direction = dirs.empty() ? glm::dvec3(0) : dirs[0];
        last_direction = dirs.empty() ? glm::dvec3(0) : dirs.back();
        const std::size_t nc = atm.channels();
        if (out.size() != dirs.size() * nc) throw std::logic_error("bad out size");
        if (kind_ == Cancelling && progress && !progress->report(0.5)) throw Cancelled();
        for (std::size_t i = 0; i < dirs.size(); ++i)
            for (std::size_t c = 0; c < nc; ++c) {
                float v = 0.0f;
                if (kind_ == Constant) v = 0.01f * float(c + 1);
                if (kind_ == Zenith) v = float(1.0 + dirs[i].z);
                out[i * nc + c] = v;
            }
        if (kind_ == NaNAtOne && !dirs.empty()) out[nc * (dirs.size() / 2)] = std::nanf("");
    }
    mutable int calls = 0;
    mutable std::size_t last_count = 0;
    mutable glm::dvec3 first_direction{0}, last_direction{0};

private:
    Kind kind_;
};

Observer sun_at(double elevation_deg, double azimuth_deg = 0.0, double altitude_m = 0.0) {
    Observer o;
    o.altitude_m = altitude_m;
    const double e = elevation_deg * kDegree, a = azimuth_deg * kDegree;
    o.sun_direction = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
    return o;
}

// Sum over the image of value x pixel solid angle, per channel.
std::vector<double> integral(const SkyImage& im) {
    std::vector<double> sum(im.channels(), 0.0);
    for (int j = 0; j < im.height; ++j) {
        const double omega = equirect_pixel_solid_angle(j, im.width, im.height);
        for (int i = 0; i < im.width; ++i)
            for (std::size_t c = 0; c < im.channels(); ++c)
                sum[c] += omega * im.pixels[(std::size_t(j) * im.width + i) * im.channels() + c];
    }
    return sum;
}

bool all_finite(const SkyImage& im) {
    for (float v : im.pixels)
        if (!std::isfinite(v)) return false;
    return true;
}

class CancelAt final : public Progress {
public:
    bool report(double) override { return false; }
};

}  // namespace

TEST(SkyImage, LayoutAndOneCallWithEveryPixel) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky sky(FakeSky::Zenith);
    SkyImageOptions opt;
    opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
    opt.sun_disc = false;
    opt.output = SkyImageOptions::Output::Spectral;
    const SkyImage im = render_equirect_sky(sky, atm, sun_at(30), 64, opt);
    EXPECT_EQ(im.width, 64);
    EXPECT_EQ(im.height, 32);
    EXPECT_EQ(sky.calls, 1);
    EXPECT_EQ(sky.last_count, 64u * 32u);
    // Directions in pixel order, top row first, left to right.
    EXPECT_NEAR(glm::length(sky.first_direction - equirect_pixel_direction(0, 0, 64, 32)), 0, 1e-15);
    EXPECT_NEAR(glm::length(sky.last_direction - equirect_pixel_direction(63, 31, 64, 32)), 0, 1e-15);
    ASSERT_EQ(im.channel_names, (std::vector<std::string>{"S0.680nm", "S0.550nm", "S0.440nm"}));
    // Radiance 1 + z: brightest on the top row.
    for (int j = 0; j < 32; ++j) {
        const double expect = 1.0 + equirect_pixel_direction(5, j, 64, 32).z;
        EXPECT_NEAR(im.pixels[(std::size_t(j) * 64 + 5) * 3 + 1], expect, 1e-6);
    }
    EXPECT_EQ(spectral_channel_name(550.5), "S0.550,5nm");
}

TEST(SkyImage, SkyIsConvertedWithTheSkyLambdaPower) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky sky(FakeSky::Constant);
    SkyImageOptions opt;
    opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
    opt.sun_disc = false;
    const SkyImage im = render_equirect_sky(sky, atm, sun_at(30), 16, opt);
    ASSERT_EQ(im.channel_names, (std::vector<std::string>{"R", "G", "B"}));
    const std::vector<float> s = {0.01f, 0.02f, 0.03f};
    const auto rgb = SpectrumToRgb(atm.wavelengths_nm, -3.0).convert(s);
    for (std::size_t p = 0; p < 16u * 8u; ++p)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(im.pixels[p * 3 + c], rgb[c], 1e-6 * rgb[c]);
}

TEST(SkyImage, SunDiscCarriesTheDirectIrradianceAtEveryResolution) {
    // Integral of the image over the sphere = direct irradiance of sun_radiometry, per
    // wavelength (spectral output) and after conversion (RGB, lambda power 0), with the
    // disc smaller than a pixel (64 wide: 0.098 rad pixels vs 0.0047 rad radius) or a few
    // pixels across (2048), at the zenith (a pole of the mapping), high, low, cut by the
    // horizon, and from 20 km up.
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky zero(FakeSky::Zero);
    const SpectrumToRgb sun_rgb(atm.wavelengths_nm, 0.0);
    struct Case {
        double elevation_deg, azimuth_deg, altitude_m;
    };
    const double a_deg = atm.sun_angular_radius_rad / kDegree;
    for (const Case k :
         {Case{90, 0, 0}, Case{30, 10, 0}, Case{3, -100, 0}, Case{0.5 * a_deg, 45, 0}, Case{0, 180, 0},
          Case{-0.9 * a_deg, 12.3, 0}, Case{-4.0, 77, 20e3}, Case{89.8, 33, 0}}) {
        const Observer obs = sun_at(k.elevation_deg, k.azimuth_deg, k.altitude_m);
        const SunRadiometry sun = sun_radiometry(atm, obs);
        ASSERT_GT(sun.visible_fraction, 0.0);
        for (int width : {64, 512, 2048}) {
            SkyImageOptions opt;
            opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
            opt.output = SkyImageOptions::Output::Spectral;
            const SkyImage im = render_equirect_sky(zero, atm, obs, width, opt);
            const std::vector<double> e = integral(im);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(e[c] / sun.direct_irradiance[c], 1.0, 2e-5)
                    << "elevation " << k.elevation_deg << " width " << width << " channel " << c;
            opt.output = SkyImageOptions::Output::Rgb;
            const SkyImage rgb = render_equirect_sky(zero, atm, obs, width, opt);
            const std::vector<float> d(sun.direct_irradiance.begin(), sun.direct_irradiance.end());
            const auto expect = sun_rgb.convert(d);
            const std::vector<double> got = integral(rgb);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c] / expect[c], 1.0, 2e-5)
                    << "elevation " << k.elevation_deg << " width " << width << " channel " << c;
        }
    }
}

TEST(SkyImage, SunDiscIsALimbDarkenedDiscWhenResolved) {
    // A large sun (0.05 rad) on a 1024-wide image: 8 pixels of radius. The pixel at the
    // disc centre holds E T / Omega_sun times the limb darkening near the centre; pixels
    // well outside hold nothing; the disc is brighter in the middle than near the limb.
    Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    atm.sun_angular_radius_rad = 0.05;
    const FakeSky zero(FakeSky::Zero);
    const int W = 1024, H = 512;
    // Sun at the centre of pixel (600, 200).
    const glm::dvec3 s = equirect_pixel_direction(600, 200, W, H);
    Observer obs;
    obs.sun_direction = s;
    SkyImageOptions opt;
    opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
    opt.output = SkyImageOptions::Output::Spectral;
    const SkyImage im = render_equirect_sky(zero, atm, obs, W, opt);
    const SunRadiometry sun = sun_radiometry(atm, obs);
    const double omega_sun = kTwoPi * (1.0 - std::cos(atm.sun_angular_radius_rad));
    auto at = [&](int i, int j, int c) { return im.pixels[(std::size_t(j) * W + i) * 3 + c]; };
    for (int c = 0; c < 3; ++c) {
        const LimbDarkening ld(atm.sun_angular_radius_rad, atm.wavelengths_nm[c]);
        const double mean = sun.direct_irradiance[c] / omega_sun;
        // The centre pixel averages LD over a pixel 0.12 alpha wide: within 1 % of LD(0).
        EXPECT_NEAR(at(600, 200, c) / (mean * ld.centre()), 1.0, 0.01) << c;
        // Half-way to the limb (4 pixels = 0.49 alpha along the row's great circle, a bit
        // less because the row is at 20 degrees elevation... use the exact angle).
        const glm::dvec3 d = equirect_pixel_direction(600, 204, W, H);
        const double rho = std::acos(glm::dot(d, s));
        EXPECT_NEAR(at(600, 204, c) / (mean * ld(rho)), 1.0, 0.03) << c;
        EXPECT_LT(at(600, 206, c), at(600, 200, c));
        EXPECT_EQ(at(600, 215, c), 0.0f);  // 15 pixels away: off the disc
        EXPECT_EQ(at(620, 200, c), 0.0f);
    }
}

TEST(SkyImage, ExposureScalesEverythingAndDiscCanBeLeftOut) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky sky(FakeSky::Constant);
    SkyImageOptions one, two, none;
    one.ground = two.ground = none.ground = false;
    two.exposure = 2.0;
    none.sun_disc = false;
    const SkyImage a = render_equirect_sky(sky, atm, sun_at(40), 128, one);
    const SkyImage b = render_equirect_sky(sky, atm, sun_at(40), 128, two);
    const SkyImage c = render_equirect_sky(sky, atm, sun_at(40), 128, none);
    double diff = 0.0;
    for (std::size_t k = 0; k < a.pixels.size(); ++k) {
        EXPECT_FLOAT_EQ(b.pixels[k], 2.0f * a.pixels[k]);
        diff += a.pixels[k] - c.pixels[k];
    }
    EXPECT_GT(diff, 0.0);  // the disc added light
}

TEST(SkyImage, NeverNaNAndNonFiniteMethodOutputIsAnError) {
    const FakeSky constant(FakeSky::Constant);
    for (const char* preset : {"bruneton2017", "mars"}) {
        for (bool spectral : {false, true}) {
            const Atmosphere atm =
                spectral ? Atmosphere::preset(preset, spectral_wavelengths_nm()) : Atmosphere::preset(preset);
            for (const Observer& obs : {sun_at(90), sun_at(-90), sun_at(0), sun_at(0.001),
                                        sun_at(-89.99, 0, 1e8), sun_at(10, 0, 1e8), sun_at(45, 180, 5e4)}) {
                for (int width : {4, 6, 256}) {
                    SkyImageOptions opt;
                    opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
                    opt.exposure = 1e6;
                    const SkyImage im = render_equirect_sky(constant, atm, obs, width, opt);
                    EXPECT_TRUE(all_finite(im)) << preset << " width " << width;
                }
            }
        }
    }
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky nan_sky(FakeSky::NaNAtOne);
    EXPECT_THROW(render_equirect_sky(nan_sky, atm, sun_at(30), 16), std::runtime_error);
}

TEST(SkyImage, CancellationPropagates) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky sky(FakeSky::Cancelling);
    CancelAt cancel;
    EXPECT_THROW(render_equirect_sky(sky, atm, sun_at(30), 16, {}, &cancel), Cancelled);
}

TEST(SkyImage, RejectsBadInput) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky sky(FakeSky::Zero);
    EXPECT_THROW(render_equirect_sky(sky, atm, sun_at(30), 7), InvalidArgument);
    EXPECT_THROW(render_equirect_sky(sky, atm, sun_at(30), 2), InvalidArgument);
    EXPECT_THROW(render_equirect_sky(sky, atm, sun_at(30), 20000), InvalidArgument);
    SkyImageOptions opt;
    opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
    for (double e : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
        opt.exposure = e;
        EXPECT_THROW(render_equirect_sky(sky, atm, sun_at(30), 16, opt), InvalidArgument) << e;
    }
    Observer bad = sun_at(30);
    bad.sun_direction = {0, 0, 0};
    EXPECT_THROW(render_equirect_sky(sky, atm, bad, 16), InvalidArgument);
    // RGB needs three wavelengths at least.
    Atmosphere two = Atmosphere::preset("bruneton2017", {500.0, 600.0});
    EXPECT_THROW(render_equirect_sky(sky, two, sun_at(30), 16), InvalidArgument);
}

TEST(SkyImage, SubPixelDiscLandsInItsPixel) {
    // 64 wide: pixels of 0.098 rad, 20 sun radii. A sun at a pixel centre puts all its
    // energy into that pixel.
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const FakeSky zero(FakeSky::Zero);
    Observer obs;
    obs.sun_direction = equirect_pixel_direction(40, 9, 64, 32);
    SkyImageOptions opt;
    opt.ground = false;  // the sky and the disc alone (the ground: test_ground.cpp)
    opt.output = SkyImageOptions::Output::Spectral;
    const SkyImage im = render_equirect_sky(zero, atm, obs, 64, opt);
    const SunRadiometry sun = sun_radiometry(atm, obs);
    for (int c = 0; c < 3; ++c) {
        const double v = im.pixels[(9 * 64 + 40) * 3 + c];
        EXPECT_NEAR(v * equirect_pixel_solid_angle(9, 64, 32) / sun.direct_irradiance[c], 1.0, 1e-5);
    }
    std::size_t lit = 0;
    for (float v : im.pixels) lit += v > 0.0f;
    EXPECT_EQ(lit, 3u);
}

TEST(SkyImage, LutHdriAt2048IsFiniteAndKeepsTheDiscEnergy) {
    // The real path: the lut method, every pixel in one call, RGB with the disc. (Its speed
    // is measured in bench/bench_sky.cpp, not here.)
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const std::unique_ptr<SkyMethod> lut = make_sky_method("lut");
    const Observer obs = sun_at(20, 45);
    const SkyImage im = render_equirect_sky(*lut, atm, obs, 2048);
    EXPECT_TRUE(all_finite(im));
    // Energy: the image integral minus the sky's equals the direct irradiance (RGB, p = 0).
    SkyImageOptions no_disc;
    no_disc.sun_disc = false;
    const SkyImage sky = render_equirect_sky(*lut, atm, obs, 2048, no_disc);
    const SunRadiometry sun = sun_radiometry(atm, obs);
    const std::vector<float> d(sun.direct_irradiance.begin(), sun.direct_irradiance.end());
    const auto expect = SpectrumToRgb(atm.wavelengths_nm, 0.0).convert(d);
    const std::vector<double> a = integral(im), b = integral(sky);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR((a[c] - b[c]) / expect[c], 1.0, 1e-4) << c;
}
