// SPDX-License-Identifier: Apache-2.0
// The night sky's own light: airglow and zodiacal light (include/welkin/night/night_glow.hpp
// has the model and its sources).
#include "welkin/night/night_glow.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "air_transmittance.hpp"
#include "layer.hpp"
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/gamut.hpp"

namespace welkin {
namespace {

// Leinert et al. 1998, Table 16: zodiacal light seen from the Earth, S10, by helioecliptic
// longitude (rows) and ecliptic latitude (columns); the last column, the ecliptic pole,
// is their text's 60 S10. Cells the table leaves empty (within 15 degrees of the sun)
// hold the nearest filled cell at the same latitude (header comment).
constexpr std::array<double, 19> kZodiLongitudesDeg{0,  5,  10, 15,  20,  25,  30,  35,  40, 45,
                                                    60, 75, 90, 105, 120, 135, 150, 165, 180};
constexpr std::array<double, 11> kZodiLatitudesDeg{0, 5, 10, 15, 20, 25, 30, 45, 60, 75, 90};
constexpr double kZodiS10[19][11] = {
    {9000, 5300, 3700, 2450, 1260, 770, 500, 215, 117, 78, 60},  // 0 (first 3: filled)
    {9000, 5300, 3700, 2300, 1200, 740, 490, 212, 117, 78, 60},  // 5 (first 3: filled)
    {9000, 5300, 3700, 1930, 1070, 675, 460, 206, 116, 78, 60},  // 10 (first 2: filled)
    {9000, 5300, 2690, 1450, 870, 590, 410, 196, 114, 78, 60},   // 15
    {5000, 3500, 1880, 1100, 710, 495, 355, 185, 110, 77, 60},   // 20
    {3000, 2210, 1350, 860, 585, 425, 320, 174, 106, 76, 60},    // 25
    {1940, 1460, 955, 660, 480, 365, 285, 162, 102, 74, 60},     // 30
    {1290, 990, 710, 530, 400, 310, 250, 151, 98, 73, 60},       // 35
    {925, 735, 545, 415, 325, 264, 220, 140, 94, 72, 60},        // 40
    {710, 570, 435, 345, 278, 228, 195, 130, 91, 70, 60},        // 45
    {395, 345, 275, 228, 190, 163, 143, 105, 81, 67, 60},        // 60
    {264, 248, 210, 177, 153, 134, 118, 91, 73, 64, 60},         // 75
    {202, 196, 176, 151, 130, 115, 103, 81, 67, 62, 60},         // 90
    {166, 164, 154, 133, 117, 104, 93, 75, 64, 60, 60},          // 105
    {147, 145, 138, 120, 108, 98, 88, 70, 60, 58, 60},           // 120
    {140, 139, 130, 115, 105, 95, 86, 70, 60, 57, 60},           // 135
    {140, 139, 129, 116, 107, 99, 91, 75, 62, 56, 60},           // 150
    {153, 150, 140, 129, 118, 110, 102, 81, 64, 56, 60},         // 165
    {180, 166, 152, 139, 127, 116, 105, 82, 65, 56, 60},         // 180
};

// Cell index and fraction of x on the grids above: 5-degree steps up to `knee`, 15 beyond.
std::pair<int, double> zodi_cell(double x, double knee, int last) {
    const double u = x < knee ? x / 5.0 : knee / 5.0 + (x - knee) / 15.0;
    const int i = std::clamp(int(u), 0, last - 1);
    return {i, std::clamp(u - i, 0.0, 1.0)};
}

// One S10 at 545 nm: V = 10 mag over a square degree = 10 + 2.5 log10(3600^2) mag/arcsec^2.
constexpr double kS10VMag = 27.78151250383644;

// Photon energy h c / lambda (J), lambda in nm.
double photon_energy_j(double lambda_nm) {
    constexpr double kPlanck = 6.62607015e-34, kLightSpeed = 299792458.0;  // SI, exact
    return kPlanck * kLightSpeed / (lambda_nm * 1e-9);
}

// 1 R (rayleigh) of a line or 1 R/nm of a continuum as photons s^-1 m^-2 sr^-1 (nm^-1).
constexpr double kRayleighPhotonRadiance = 1e10 / (4.0 * kPi);

// Header comment: O I 557.7, Na D (the doublet's centre), O I 630.0 and 636.4.
constexpr std::array<AirglowLine, 4> kAirglowLines{
    {{557.7, 250.0}, {589.3, 50.0}, {630.0, 60.0}, {636.4, 20.0}}};

// Linear interpolation of per-channel values at x (monotonic wavelengths; beyond the
// ends, the end channel's value).
double interpolate_channels(std::span<const double> wl, std::span<const double> values, double x) {
    const std::size_t n = wl.size();
    if (n == 1) return values[0];
    for (std::size_t c = 0; c + 1 < n; ++c) {
        const double a = wl[c], b = wl[c + 1];
        if ((x - a) * (x - b) <= 0.0) return values[c] + (values[c + 1] - values[c]) * (x - a) / (b - a);
    }
    return std::abs(x - wl.front()) < std::abs(x - wl.back()) ? values.front() : values.back();
}

}  // namespace

std::span<const AirglowLine> airglow_lines() { return kAirglowLines; }

double v_surface_brightness_to_radiance(double v_mag_per_arcsec2) {
    require_in_range("v_mag_per_arcsec2", v_mag_per_arcsec2, -30.0, 40.0);
    constexpr double kV0 = 3.631e-11;              // W m^-2 nm^-1 at V = 0, 545 nm
    constexpr double kArcsec2PerSr = 4.254517e10;  // (180 x 3600 / pi)^2
    return kV0 * std::pow(10.0, -0.4 * v_mag_per_arcsec2) * kArcsec2PerSr;
}

double van_rhijn_factor(double cos_zenith, double observer_radius_m, double layer_radius_m) {
    const double q = observer_radius_m / layer_radius_m;
    const double sin2_z = std::max(0.0, 1.0 - cos_zenith * cos_zenith);
    return 1.0 / std::sqrt(std::max(1e-12, 1.0 - q * q * sin2_z));
}

std::vector<double> airglow_zenith_radiance(std::span<const double> wl) {
    const std::size_t n = wl.size();
    if (n == 0) throw InvalidArgument("wavelengths_nm", "must not be empty");
    std::vector<double> out(n);
    for (std::size_t c = 0; c < n; ++c)
        out[c] = kAirglowContinuumRayleighPerNm * kRayleighPhotonRadiance * photon_energy_j(wl[c]);
    if (n < 2) return out;
    // Channels by increasing wavelength, and each one's width in the interpolant's integral.
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    if (wl[1] < wl[0]) std::reverse(order.begin(), order.end());
    std::vector<double> width(n);
    for (std::size_t k = 0; k < n; ++k) {
        const double lo = wl[order[k > 0 ? k - 1 : k]], hi = wl[order[k + 1 < n ? k + 1 : k]];
        width[order[k]] = 0.5 * (hi - lo);
    }
    for (const AirglowLine& line : kAirglowLines) {
        const double radiance = line.rayleigh * kRayleighPhotonRadiance * photon_energy_j(line.lambda_nm);
        // Beyond the end channels: all of it on the nearer end.
        const std::size_t first = order.front(), last = order.back();
        if (line.lambda_nm <= wl[first] || line.lambda_nm >= wl[last]) {
            const std::size_t c = line.lambda_nm <= wl[first] ? first : last;
            out[c] += radiance / width[c];
            continue;
        }
        for (std::size_t k = 0; k + 1 < n; ++k) {
            const std::size_t a = order[k], b = order[k + 1];
            if (line.lambda_nm < wl[a] || line.lambda_nm > wl[b]) continue;
            const double f = (wl[b] - line.lambda_nm) / (wl[b] - wl[a]);
            out[a] += radiance * f / width[a];
            out[b] += radiance * (1.0 - f) / width[b];
            break;
        }
    }
    return out;
}

double zodiacal_light_s10(double helioecliptic_longitude_deg, double ecliptic_latitude_deg) {
    require_finite("helioecliptic_longitude_deg", helioecliptic_longitude_deg);
    require_finite("ecliptic_latitude_deg", ecliptic_latitude_deg);
    double lon = std::fmod(std::abs(helioecliptic_longitude_deg), 360.0);
    if (lon > 180.0) lon = 360.0 - lon;
    const double lat = std::min(std::abs(ecliptic_latitude_deg), 90.0);
    const auto [i, fi] = zodi_cell(lon, 45.0, int(kZodiLongitudesDeg.size()) - 1);
    const auto [j, fj] = zodi_cell(lat, 30.0, int(kZodiLatitudesDeg.size()) - 1);
    const auto row = [&](int r) { return kZodiS10[r][j] * (1.0 - fj) + kZodiS10[r][j + 1] * fj; };
    return row(i) * (1.0 - fi) + row(i + 1) * fi;
}

namespace {

// The glow's light into `sink` (an image `width` wide in the output's channels), a row at a
// time: each row is computed (and gamut-mapped) in a buffer of its own, then added.
void add_glow_light(const night::LayerSink& sink, const Atmosphere& atm, const Observer& observer, int width,
                    SkyImageOptions::Output output, ColorSpace color_space, const NightGlowOptions& glow) {
    const int height = width / 2;
    const std::size_t nc = atm.channels();
    const bool rgb = output == SkyImageOptions::Output::Rgb;
    const std::size_t out_nc = rgb ? 3 : nc;
    if (!glow.airglow && !glow.zodiacal_light) return;

    // Above the air, per channel: the airglow at the zenith; the zodiacal light per S10
    // (the sun's shape, 1 S10 at 500 nm) and its reddening's part (f_co - 1 at 30 degrees).
    const auto& wl = atm.wavelengths_nm;
    std::vector<double> air_glow(nc, 0.0), zodi(nc, 0.0), zodi_red(nc, 0.0);
    if (glow.airglow) air_glow = airglow_zenith_radiance(wl);
    if (glow.zodiacal_light) {
        const double sun_545 = interpolate_channels(wl, atm.solar_irradiance, 545.0);
        const double sun_500 = interpolate_channels(wl, atm.solar_irradiance, 500.0);
        const double s10_500 = v_surface_brightness_to_radiance(kS10VMag) * sun_500 / sun_545;
        for (std::size_t c = 0; c < nc; ++c) {
            zodi[c] = s10_500 * atm.solar_irradiance[c] / sun_500;
            zodi_red[c] = zodi[c] * (wl[c] < 500.0 ? 1.2 : 0.8) * std::log(wl[c] / 500.0);
        }
    }
    // The reddening's weight at elongation eps: 1 up to 30 degrees, 0.75 from 90 (the
    // coefficients 1.2/0.8 become 0.9/0.6), linear between.
    const auto reddening_weight = [](double cos_eps) {
        if (cos_eps >= 0.8660254037844387) return 1.0;
        if (cos_eps <= 0.0) return 0.75;
        return 1.0 - 0.25 * (std::acos(cos_eps) / kDegree - 30.0) / 60.0;
    };

    const night::TransmittanceByElevation air(atm, observer.altitude_m);
    const double r_obs = atm.bottom_radius_m + observer.altitude_m;
    const double r_layer = atm.bottom_radius_m + kAirglowHeight_m;
    std::optional<SpectrumToRgb> to_rgb;
    if (rgb) to_rgb.emplace(wl, 0.0, color_space);  // smooth spectra and lines alike
    const std::size_t m_nc = rgb ? 3 : nc;
    const auto to_out = [&](const std::vector<double>& spectrum, std::vector<double>& out) {
        if (!rgb) {
            out = spectrum;
            return;
        }
        const std::vector<double>& m = to_rgb->matrix();
        out.assign(3, 0.0);
        for (std::size_t k = 0; k < 3; ++k)
            for (std::size_t c = 0; c < nc; ++c) out[k] += m[k * nc + c] * spectrum[c];
    };

    // The zodiacal light's S10 and reddening weight on a grid of nodes every `step` pixels
    // (a power of two dividing the width, about 1.4 degrees apart at most: the table's
    // cells are 5-15 degrees), interpolated bilinearly between them; the seam wraps.
    int step = 1;
    while (step * 2 <= width / 256 && width % (step * 2) == 0) step *= 2;
    const int nodes_x = width / step, nodes_y = (height - 1) / step + 2;
    std::vector<double> node_s10(std::size_t(nodes_x) * std::size_t(nodes_y), kZodiS10[0][10]);
    std::vector<double> node_red(node_s10.size(), 0.75);  // no moment: the pole's, 90 degrees away
    const std::optional<EclipticFrame>& ecl = glow.ecliptic;
    if (glow.zodiacal_light && ecl) {
        const auto& m = ecl->enu_to_ecliptic;
        const double sun_lon = ecl->sun_longitude_deg * kDegree;
        for (int l = 0; l < nodes_y; ++l)
            for (int k = 0; k < nodes_x; ++k) {
                // Node (k, l) is pixel (k step, l step)'s centre (rows past the bottom: the
                // bottom row's, below the horizon anyway).
                const glm::dvec3 d =
                    equirect_pixel_direction(k * step, std::min(l * step, height - 1), width, height);
                const double ex = m[0][0] * d.x + m[0][1] * d.y + m[0][2] * d.z;
                const double ey = m[1][0] * d.x + m[1][1] * d.y + m[1][2] * d.z;
                const double ez = m[2][0] * d.x + m[2][1] * d.y + m[2][2] * d.z;
                const double d_lon = std::atan2(ey, ex) - sun_lon;
                const double beta = std::atan2(ez, std::hypot(ex, ey));
                const std::size_t n = std::size_t(l) * std::size_t(nodes_x) + std::size_t(k);
                node_s10[n] = zodiacal_light_s10(d_lon / kDegree, beta / kDegree);
                node_red[n] = reddening_weight(std::cos(beta) * std::cos(d_lon));
            }
    }
    const double inv_step = 1.0 / step;

    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        std::vector<double> t(nc), a(nc), z0(nc), z1(nc), a_out, z0_out, z1_out;
        std::vector<float> row(std::size_t(width) * out_nc);
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const double sin_e = equirect_pixel_direction(0, j, width, height).z;
            if (!air(sin_e, t)) continue;  // the ground
            const double vr = van_rhijn_factor(sin_e, r_obs, r_layer);
            for (std::size_t c = 0; c < nc; ++c) {
                a[c] = air_glow[c] * vr * t[c];
                z0[c] = glow.zodiacal_light ? zodi[c] * t[c] : 0.0;
                z1[c] = glow.zodiacal_light ? zodi_red[c] * t[c] : 0.0;
            }
            to_out(a, a_out);
            to_out(z0, z0_out);
            to_out(z1, z1_out);
            const int l = j / step;
            const double fy = (j - l * step) * inv_step;
            const double* s_top = node_s10.data() + std::size_t(l) * std::size_t(nodes_x);
            const double* r_top = node_red.data() + std::size_t(l) * std::size_t(nodes_x);
            const double* s_bot = s_top + nodes_x;
            const double* r_bot = r_top + nodes_x;
            for (int i = 0; i < width; ++i) {
                const int k = i / step, k1 = (k + 1) % nodes_x;
                const double fx = (i - k * step) * inv_step;
                const double w00 = (1.0 - fx) * (1.0 - fy), w10 = fx * (1.0 - fy), w01 = (1.0 - fx) * fy,
                             w11 = fx * fy;
                const double s10 = w00 * s_top[k] + w10 * s_top[k1] + w01 * s_bot[k] + w11 * s_bot[k1];
                const double sr = w00 * s_top[k] * r_top[k] + w10 * s_top[k1] * r_top[k1] +
                                  w01 * s_bot[k] * r_bot[k] + w11 * s_bot[k1] * r_bot[k1];
                float* px = row.data() + std::size_t(i) * out_nc;
                for (std::size_t c = 0; c < m_nc; ++c)
                    px[c] = float(a_out[c] + s10 * z0_out[c] + sr * z1_out[c]);
            }
            if (rgb) gamut_map(row.data(), std::size_t(width), to_rgb->luminance_weights());
            const std::size_t first = std::size_t(j) * std::size_t(width);
            for (std::size_t i = 0; i < std::size_t(width); ++i)
                for (std::size_t c = 0; c < out_nc; ++c) sink.add(first + i, c, row[i * out_nc + c]);
        }
    });
}

}  // namespace

std::vector<float> night_glow_pixels(const Atmosphere& atm, const Observer& observer, int width,
                                     SkyImageOptions::Output output, ColorSpace color_space,
                                     const NightGlowOptions& glow) {
    const std::size_t out_nc = output == SkyImageOptions::Output::Rgb ? 3 : atm.channels();
    std::vector<float> pixels = night::blank_layer(width, out_nc);
    add_glow_light(night::sink_into(pixels, out_nc), atm, observer, width, output, color_space, glow);
    return pixels;
}

void add_night_glow(SkyImage& image, const Atmosphere& atm, const Observer& observer,
                    const SkyImageOptions& options, const NightGlowOptions& glow) {
    add_glow_light(night::sink_into(image, options.exposure), atm, observer, image.width, options.output,
                   options.color_space, glow);
}

}  // namespace welkin
