// SPDX-License-Identifier: Apache-2.0
// The sky with the moon (include/welkin/night/moonlit_sky.hpp).
#include "welkin/night/moonlit_sky.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "layer.hpp"
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "welkin/astro/moonlight.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/sun.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"

namespace welkin {
namespace {

bool finite_nonzero(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) &&
           (v.x != 0.0 || v.y != 0.0 || v.z != 0.0);
}

}  // namespace

void Moon::validate() const {
    if (!finite_nonzero(direction))
        throw InvalidArgument("moon.direction", "must be a finite non-zero vector");
    if (!finite_nonzero(sun_from_moon))
        throw InvalidArgument("moon.sun_from_moon", "must be a finite non-zero vector");
    require_in_range("moon.angular_radius_rad", angular_radius_rad, 1e-4, 0.05, "rad");
    require_in_range("moon.irradiance_ratio", irradiance_ratio, 0.0, 1e-3);
}

namespace {

// The disc's pixels: their indices (row * width + column) and values (out channels each).
struct DiscPixels {
    std::vector<std::size_t> pixel;
    std::vector<float> values;
};

DiscPixels disc_pixels(const Atmosphere& atm, const Observer& observer, const Moon& moon, int width,
                       SkyImageOptions::Output output) {
    moon.validate();
    const int height = width / 2;
    const std::size_t nc = atm.channels();
    const bool rgb = output == SkyImageOptions::Output::Rgb;
    DiscPixels pixels;
    if (!(moon.irradiance_ratio > 0.0)) return pixels;

    const glm::dvec3 m = glm::normalize(moon.direction), s = glm::normalize(moon.sun_from_moon);
    const double alpha = moon.angular_radius_rad;
    // The air towards the moon: sun_radiometry for a "sun" of the moon's size there.
    Atmosphere moon_atm = atm;
    moon_atm.sun_angular_radius_rad = alpha;
    Observer mo = observer;
    mo.sun_direction = m;
    const SunRadiometry air = sun_radiometry(moon_atm, mo.validated());
    std::vector<double> irradiance(nc);  // the whole lit disc's, through the air
    for (std::size_t c = 0; c < nc; ++c)
        irradiance[c] = atm.solar_irradiance[c] * moon.irradiance_ratio * air.transmittance[c];

    // The cap's bounding box in elevation and u (as the sun's disc, sky_image.cpp).
    const double e_m = std::asin(clamp_cosine(m.z));
    const double dv_angle = kPi / height;
    const double e_lo = e_m - alpha, e_hi = e_m + alpha;
    const int j0 = std::max(0, int(std::floor((0.5 * kPi - e_hi) / dv_angle)));
    const int j1 = std::min(height - 1, int(std::floor((0.5 * kPi - e_lo) / dv_angle)));
    int i0 = 0, ncols = width;
    double u_lo = 0.0, u_hi = 1.0;
    bool all_u = true;
    if (e_hi < 0.5 * kPi && e_lo > -0.5 * kPi) {
        const double half = std::asin(std::min(1.0, std::sin(alpha) / std::cos(e_m))) / kTwoPi;
        const double u_c = direction_to_equirect(m).x;
        const int a = int(std::floor((u_c - half) * width)), b = int(std::floor((u_c + half) * width));
        if (b - a + 1 < width) {
            all_u = false;
            u_lo = u_c - half;
            u_hi = u_c + half;
            i0 = a;
            ncols = b - a + 1;
        }
    }
    const int nrows = j1 - j0 + 1;
    const std::size_t npix = std::size_t(std::max(0, nrows)) * std::size_t(ncols);
    const double r = atm.bottom_radius_m + observer.altitude_m;
    const std::array<double, 3> ma{m.x, m.y, m.z}, sa{s.x, s.y, s.z};
    // Per pixel: the Lommel-Seeliger radiance integrated over its part of the disc, in
    // front of the ground (visible) and in all (the whole disc's normalisation).
    std::vector<double> visible(npix, 0.0), all(npix, 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, npix), [&](const auto& range) {
        for (std::size_t q = range.begin(); q != range.end(); ++q) {
            const int j = j0 + int(q / std::size_t(ncols));
            const int ii = i0 + int(q % std::size_t(ncols));
            const double e_top = std::min(0.5 * kPi - dv_angle * j, e_hi);
            const double e_bot = std::max(0.5 * kPi - dv_angle * (j + 1), e_lo);
            const double pu0 = double(ii) / width, pu1 = double(ii + 1) / width;
            const double u0 = all_u ? pu0 : std::max(pu0, u_lo), u1 = all_u ? pu1 : std::min(pu1, u_hi);
            if (!(e_top > e_bot) || !(u1 > u0)) continue;
            const double cos_max =
                (e_top >= 0.0 && e_bot <= 0.0) ? 1.0 : std::max(std::cos(e_top), std::cos(e_bot));
            const double de = e_top - e_bot, dphi = kTwoPi * (u1 - u0);
            const int kv = std::clamp(int(std::ceil(8.0 * de / alpha)), 2, 512);
            const int ku = std::clamp(int(std::ceil(8.0 * cos_max * dphi / alpha)), 2, 512);
            const double cell = dphi / ku * de / kv;
            for (int b = 0; b < kv; ++b) {
                const double e = e_top - de * (b + 0.5) / kv;
                const double ce = std::cos(e), se = std::sin(e);
                const bool hidden = ray_hits_ground(r, se, atm.bottom_radius_m);
                for (int a = 0; a < ku; ++a) {
                    const double phi = kPi - kTwoPi * (u0 + (u1 - u0) * (a + 0.5) / ku);
                    const std::array<double, 3> d{ce * std::cos(phi), ce * std::sin(phi), se};
                    const double w = moon_disc_relative_radiance(d, ma, alpha, sa) * ce * cell;
                    all[q] += w;
                    if (!hidden) visible[q] += w;
                }
            }
        }
    });
    double total = 0.0;
    for (double w : all) total += w;
    if (!(total > 0.0)) return pixels;  // a new moon: no lit part faces the observer

    std::optional<SpectrumToRgb> to_rgb;
    if (rgb) to_rgb.emplace(atm.wavelengths_nm, 0.0);  // moonlight has the sun's spectrum
    std::vector<float> spectrum(nc);
    for (std::size_t q = 0; q < npix; ++q) {
        if (!(visible[q] > 0.0)) continue;
        const int j = j0 + int(q / std::size_t(ncols));
        const int i = ((i0 + int(q % std::size_t(ncols))) % width + width) % width;
        const double omega = equirect_pixel_solid_angle(j, width, height);
        for (std::size_t c = 0; c < nc; ++c) spectrum[c] = float(irradiance[c] * visible[q] / total / omega);
        pixels.pixel.push_back(std::size_t(j) * std::size_t(width) + std::size_t(i));
        if (rgb) {
            const std::array<double, 3> v = to_rgb->convert(spectrum);
            for (int c = 0; c < 3; ++c) pixels.values.push_back(float(v[std::size_t(c)]));
        } else {
            pixels.values.insert(pixels.values.end(), spectrum.begin(), spectrum.end());
        }
    }
    return pixels;
}

}  // namespace

std::vector<float> moon_disc_pixels(const Atmosphere& atm, const Observer& observer, const Moon& moon,
                                    int width, SkyImageOptions::Output output) {
    moon.validate();
    const std::size_t out_nc = output == SkyImageOptions::Output::Rgb ? 3 : atm.channels();
    std::vector<float> layer = night::blank_layer(width, out_nc);
    const DiscPixels disc = disc_pixels(atm, observer, moon, width, output);
    for (std::size_t k = 0; k < disc.pixel.size(); ++k)
        for (std::size_t c = 0; c < out_nc; ++c)
            layer[disc.pixel[k] * out_nc + c] += disc.values[k * out_nc + c];
    return layer;
}

MoonDiscModel moon_disc_model(const Atmosphere& atm, const Observer& observer, const Moon& moon) {
    moon.validate();
    atm.validate();
    const glm::dvec3 m = glm::normalize(moon.direction), s = glm::normalize(moon.sun_from_moon);
    MoonDiscModel model;
    model.phase_angle_rad = std::acos(std::clamp(-glm::dot(m, s), -1.0, 1.0));
    model.relative_integral_sr =
        moon_disc_relative_integral_far(model.phase_angle_rad, moon.angular_radius_rad);
    model.radiance_scale.assign(atm.channels(), 0.0);
    if (!(model.relative_integral_sr > 0.0) || !(moon.irradiance_ratio > 0.0)) return model;
    // The air towards the moon, as moon_disc_pixels takes it.
    Atmosphere moon_atm = atm;
    moon_atm.sun_angular_radius_rad = moon.angular_radius_rad;
    Observer mo = observer;
    mo.sun_direction = m;
    const SunRadiometry air = sun_radiometry(moon_atm, mo.validated());
    for (std::size_t c = 0; c < atm.channels(); ++c)
        model.radiance_scale[c] = atm.solar_irradiance[c] * moon.irradiance_ratio * air.transmittance[c] /
                                  model.relative_integral_sr;
    return model;
}

Moon moon_at(const SunAndMoon& sky) {
    Moon moon;
    const auto& m = sky.moon.direction_enu;
    moon.direction = {m[0], m[1], m[2]};
    const auto& s = sky.sun_from_moon_enu;
    moon.sun_from_moon = {s[0], s[1], s[2]};
    moon.angular_radius_rad = sky.moon.angular_radius_deg * kDegree;
    moon.irradiance_ratio = sky.moon_irradiance_ratio;
    return moon;
}

SkyImage render_equirect_sky_with_moon(const SkyMethod& method, const Atmosphere& atm,
                                       const Observer& observer, const Moon& moon, int width,
                                       const SkyImageOptions& options, Progress* progress) {
    moon.validate();
    const bool moon_sky = moon.irradiance_ratio > 0.0 &&
                          glm::normalize(moon.direction).z >= std::sin(-kMoonSkyDepressionDeg * kDegree);
    SkyImage image;
    if (moon_sky && !options.clouds) {
        // The moonlit sky: every method's radiance (and the lit ground's) is linear in the
        // solar irradiance, so the sky for a "sun" in the moon's direction, scaled by the
        // ratio, is the sky lit by the moon (the same cached LUTs; colour conversion
        // linear). One pass over the image for both (sky_image.hpp, ExtraSun).
        const ExtraSun lit_by_moon{moon.direction, moon.irradiance_ratio};
        image = render_equirect_sky(method, atm, observer, std::span<const ExtraSun>(&lit_by_moon, 1), width,
                                    options, progress);
    } else {
        image = render_equirect_sky(method, atm, observer, width, options, progress);
        if (moon_sky) {
            // With clouds, the moon's sky is a render of its own. The clouds' march is linear
            // in the light too: the moon's image marches them lit from the moon, and the two
            // composites add, the clouds' transmittance being the same for both lights.
            // While the sun is up the moon's light on the clouds is left out (header): its
            // clear sky is seen through them, times their transmittance, with no second march.
            Observer lit_by_moon = observer;
            lit_by_moon.sun_direction = moon.direction;
            SkyImageOptions moon_options = options;
            moon_options.sun_disc = false;
            const bool clouds_by_sunlight = moon_clouds_left_out(observer);
            if (clouds_by_sunlight) moon_options.clouds = nullptr;
            const SkyImage moonlit =
                render_equirect_sky(method, atm, lit_by_moon.validated(), width, moon_options, progress);
            const float ratio = float(moon.irradiance_ratio);
            if (clouds_by_sunlight) {
                night::add_under_clouds(image, moonlit.pixels, ratio);
            } else {
                for (std::size_t k = 0; k < image.pixels.size(); ++k)
                    image.pixels[k] += ratio * moonlit.pixels[k];
            }
        }
    }
    if (moon_sky && moon.disc) {
        // Its pixels alone, as night::add_under_clouds adds a layer: exposure x the clouds'
        // transmittance x the value.
        const DiscPixels disc = disc_pixels(atm, observer, moon, width, options.output);
        const std::size_t nc = image.channels();
        const float e = float(options.exposure);
        for (std::size_t k = 0; k < disc.pixel.size(); ++k) {
            const std::size_t p = disc.pixel[k];
            const float t = image.cloud_transmittance.empty() ? 1.0f : image.cloud_transmittance[p];
            for (std::size_t c = 0; c < nc; ++c) image.pixels[p * nc + c] += e * t * disc.values[k * nc + c];
        }
    }
    return image;
}

}  // namespace welkin
