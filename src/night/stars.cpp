// SPDX-License-Identifier: Apache-2.0
// The stars (include/welkin/night/stars.hpp has the method and its sources).
#include "welkin/night/stars.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "air_transmittance.hpp"
#include "layer.hpp"
#include <fmt/format.h>

#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"

namespace welkin {
namespace {

constexpr CatalogueStar kHipparcos[] = {
#include "hipparcos_stars.inc"
};

// Julian date (TT) of the catalogue's epoch, J1991.25.
constexpr double kEpochJd = 2448349.0625;

// Planck's law up to a constant: lambda^-5 / (exp(hc / (lambda k T)) - 1), lambda in nm.
double planck(double lambda_nm, double temperature_k) {
    constexpr double hc_over_k = 1.438776877e7;  // nm K (second radiation constant)
    return std::pow(lambda_nm, -5.0) / std::expm1(hc_over_k / (lambda_nm * temperature_k));
}

}  // namespace

std::span<const CatalogueStar> hipparcos_stars() { return kHipparcos; }

double star_temperature_k(double b_v) {
    const double x = 0.92 * std::clamp(std::isfinite(b_v) ? b_v : 0.0, -0.4, 2.0);
    return 4600.0 * (1.0 / (x + 1.7) + 1.0 / (x + 0.62));
}

std::vector<double> star_irradiance(double v_mag, double b_v, std::span<const double> wavelengths_nm) {
    require_in_range("v_mag", v_mag, -30.0, 30.0);
    require_finite("b_v", b_v);
    const double t = star_temperature_k(b_v);
    constexpr double kV0 = 3.631e-11;  // W m^-2 nm^-1 at V = 0 (Bessell et al. 1998)
    constexpr double kVEffective_nm = 545.0;
    const double scale = kV0 * std::pow(10.0, -0.4 * v_mag) / planck(kVEffective_nm, t);
    std::vector<double> e(wavelengths_nm.size());
    for (std::size_t c = 0; c < e.size(); ++c) e[c] = scale * planck(wavelengths_nm[c], t);
    return e;
}

std::vector<Star> stars_at(const Instant& when, const Place& where, double faintest_v) {
    require_in_range("faintest_v", faintest_v, -2.0, 20.0);
    const double years = (when.tt_jd() - kEpochJd) / 365.25;
    std::vector<std::array<double, 3>> icrs;
    std::vector<const CatalogueStar*> picked;
    for (const CatalogueStar& s : kHipparcos) {
        if (s.v_mag > faintest_v) break;  // brightest first
        // Proper motion, linear on the sphere: p + t (mu_a e_alpha + mu_d e_delta), renormalised.
        const double a = s.ra_deg * kDegree, d = s.dec_deg * kDegree;
        const double ca = std::cos(a), sa = std::sin(a), cd = std::cos(d), sd = std::sin(d);
        const double ma = s.pm_ra_mas_yr * years / 3.6e6 * kDegree;
        const double md = s.pm_dec_mas_yr * years / 3.6e6 * kDegree;
        const std::array<double, 3> p{cd * ca - ma * sa - md * sd * ca, cd * sa + ma * ca - md * sd * sa,
                                      sd + md * cd};
        const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        icrs.push_back({p[0] / n, p[1] / n, p[2] / n});
        picked.push_back(&s);
    }
    const std::vector<std::array<double, 3>> enu = apparent_star_directions(when, where, icrs);
    std::vector<Star> out(enu.size());
    for (std::size_t i = 0; i < enu.size(); ++i)
        out[i] = Star{{enu[i][0], enu[i][1], enu[i][2]}, picked[i]->v_mag, picked[i]->b_v};
    return out;
}

namespace {

// Each star's light into `sink` (an image `width` wide in the output's channels).
void add_star_light(const night::LayerSink& sink, const Atmosphere& atm, const Observer& observer,
                    std::span<const Star> stars, int width, SkyImageOptions::Output output,
                    ColorSpace color_space) {
    const int height = width / 2;
    const std::size_t nc = atm.channels();
    const bool rgb = output == SkyImageOptions::Output::Rgb;
    const night::TransmittanceByElevation air(atm, observer.altitude_m);
    std::optional<SpectrumToRgb> to_rgb;
    if (rgb) to_rgb.emplace(atm.wavelengths_nm, 0.0, color_space);  // a smooth spectrum, as the sun's
    std::vector<double> transmittance(nc);
    std::vector<float> spectrum(nc);
    std::array<double, 3> value{};
    for (const Star& star : stars) {
        const glm::dvec3 d = star.direction;
        const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        if (!(len > 0.0) || !std::isfinite(len))
            throw InvalidArgument("stars.direction", "must be finite, non-zero");
        const glm::dvec3 u = d / len;
        if (!air(u.z, transmittance)) continue;
        const std::vector<double> e = star_irradiance(star.v_mag, star.b_v, atm.wavelengths_nm);
        for (std::size_t c = 0; c < nc; ++c) spectrum[c] = float(e[c] * transmittance[c]);
        if (rgb) value = to_rgb->convert(spectrum);
        // Bilinear weights around the direction's position in pixel units (centres at +0.5).
        const glm::dvec2 uv = direction_to_equirect(u);
        const double x = uv.x * width - 0.5, y = (1.0 - uv.y) * height - 0.5;
        const int i0 = int(std::floor(x)), j0 = int(std::floor(y));
        const double fx = x - i0, fy = y - j0;
        for (int dj = 0; dj < 2; ++dj) {
            // Rows off the image's top or bottom fold back onto the edge row.
            const int j = std::clamp(j0 + dj, 0, height - 1);
            const double wy = dj ? fy : 1.0 - fy;
            const double omega = equirect_pixel_solid_angle(j, width, height);
            for (int di = 0; di < 2; ++di) {
                const int i = ((i0 + di) % width + width) % width;
                const double w = wy * (di ? fx : 1.0 - fx) / omega;
                const std::size_t p = std::size_t(j) * std::size_t(width) + std::size_t(i);
                if (rgb)
                    for (std::size_t c = 0; c < 3; ++c) sink.add(p, c, float(w * value[c]));
                else
                    for (std::size_t c = 0; c < nc; ++c) sink.add(p, c, float(w * spectrum[c]));
            }
        }
    }
}

}  // namespace

std::vector<float> star_pixels(const Atmosphere& atm, const Observer& observer, std::span<const Star> stars,
                               int width, SkyImageOptions::Output output, ColorSpace color_space) {
    const std::size_t out_nc = output == SkyImageOptions::Output::Rgb ? 3 : atm.channels();
    std::vector<float> pixels = night::blank_layer(width, out_nc);
    add_star_light(night::sink_into(pixels, out_nc), atm, observer, stars, width, output, color_space);
    return pixels;
}

void add_stars(SkyImage& image, const Atmosphere& atm, const Observer& observer, std::span<const Star> stars,
               const SkyImageOptions& options) {
    if (stars.empty()) return;
    add_star_light(night::sink_into(image, options.exposure), atm, observer, stars, image.width,
                   options.output, options.color_space);
}

}  // namespace welkin
