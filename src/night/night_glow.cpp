// SPDX-License-Identifier: Apache-2.0
// The night sky's own light (include/welkin/night/night_glow.hpp has the model and its
// sources).
#include "welkin/night/night_glow.hpp"

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

double v_surface_brightness_to_radiance(double v_mag_per_arcsec2) {
    require_in_range("v_mag_per_arcsec2", v_mag_per_arcsec2, -30.0, 40.0);
    constexpr double kV0 = 3.631e-11;              // W m^-2 nm^-1 at V = 0, 545 nm
    constexpr double kArcsec2PerSr = 4.254517e10;  // (180 x 3600 / pi)^2
    return kV0 * std::pow(10.0, -0.4 * v_mag_per_arcsec2) * kArcsec2PerSr;
}

std::vector<float> night_glow_pixels(const Atmosphere& atm, const Observer& observer, int width,
                                     SkyImageOptions::Output output, ColorSpace color_space) {
    const int height = width / 2;
    const std::size_t nc = atm.channels();
    const bool rgb = output == SkyImageOptions::Output::Rgb;
    const std::size_t out_nc = rgb ? 3 : nc;
    std::vector<float> pixels = night::blank_layer(width, out_nc);

    // The zenith's spectrum: the sun's shape, V's radiance at 545 nm (linear interpolation of
    // the solar irradiance between the channels; the end channels beyond them).
    const auto& wl = atm.wavelengths_nm;
    const auto& sun = atm.solar_irradiance;
    double sun_545 = sun.front();
    const bool increasing = wl.back() > wl.front();
    for (std::size_t c = 0; c + 1 < nc; ++c) {
        const double a = wl[c], b = wl[c + 1];
        if ((545.0 - a) * (545.0 - b) <= 0.0) {
            sun_545 = sun[c] + (sun[c + 1] - sun[c]) * (545.0 - a) / (b - a);
            break;
        }
    }
    if (nc > 1 && (increasing ? 545.0 > wl.back() : 545.0 < wl.back())) sun_545 = sun.back();
    const double l_545 = v_surface_brightness_to_radiance(kDarkSkyZenithVMagArcsec2);
    const night::TransmittanceByElevation air(atm, observer.altitude_m);
    std::vector<double> t_zenith(nc), t(nc);
    air(1.0, t_zenith);
    std::optional<SpectrumToRgb> to_rgb;
    if (rgb) to_rgb.emplace(atm.wavelengths_nm, 0.0, color_space);
    std::vector<float> spectrum(nc);
    std::vector<float> row_value(out_nc);
    for (int j = 0; j < height; ++j) {
        const double sin_e = equirect_pixel_direction(0, j, width, height).z;
        if (!air(sin_e, t)) continue;  // the ground
        const double sin2_z = 1.0 - sin_e * sin_e;
        const double van_rhijn = 1.0 / std::sqrt(1.0 - 0.96 * sin2_z);
        for (std::size_t c = 0; c < nc; ++c)
            spectrum[c] =
                float(l_545 * sun[c] / sun_545 * van_rhijn * (t_zenith[c] > 0.0 ? t[c] / t_zenith[c] : 0.0));
        if (rgb) {
            const std::array<double, 3> v = to_rgb->convert(spectrum);
            for (int c = 0; c < 3; ++c) row_value[std::size_t(c)] = float(v[std::size_t(c)]);
        } else {
            std::copy(spectrum.begin(), spectrum.end(), row_value.begin());
        }
        float* row = pixels.data() + std::size_t(j) * std::size_t(width) * out_nc;
        for (int i = 0; i < width; ++i)
            std::copy(row_value.begin(), row_value.end(), row + std::size_t(i) * out_nc);
    }
    return pixels;
}

void add_night_glow(SkyImage& image, const Atmosphere& atm, const Observer& observer,
                    const SkyImageOptions& options) {
    night::add_under_clouds(
        image, night_glow_pixels(atm, observer, image.width, options.output, options.color_space),
        options.exposure);
}

}  // namespace welkin
