// Equirectangular sky images with the sun's disc; see sky_image.hpp.
#include "welkin/sky_image.hpp"

#include <algorithm>
#include <cmath>
#include <array>
#include <optional>
#include <span>
#include <stdexcept>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "welkin/color.hpp"
#include "welkin/equirect.hpp"
#include "welkin/error.hpp"
#include "welkin/geometry.hpp"
#include "welkin/math.hpp"
#include "welkin/sun.hpp"

namespace welkin {
namespace {

// Radiance values held at once: the method is called with every pixel of the image when
// (pixels x channels) fits in this many floats (128 MiB; any 3-channel image up to 4096
// wide), else with bands of whole rows, so that the 48-channel spectral mode at large
// sizes does not need gigabytes.
constexpr std::size_t kMaxValuesPerCall = std::size_t(32) << 20;

// Maps a sub-task's [0, 1] onto [lo, hi] of the host's progress.
class SubProgress final : public Progress {
public:
    SubProgress(Progress* host, double lo, double hi) : host_(host), lo_(lo), hi_(hi) {}
    bool report(double fraction) override {
        return !host_ || host_->report(lo_ + (hi_ - lo_) * clamp01(fraction));
    }

private:
    Progress* host_;
    double lo_, hi_;
};

// Adds the sun's disc to `pixels` (height x width x channels, top row first): spectral
// radiance per atmosphere wavelength in `disc` (the caller converts it), keyed by pixel.
struct DiscSplat {
    std::vector<std::size_t> pixel;   // index y * width + x
    std::vector<double> radiance;     // (pixel.size(), channels), W m^-2 sr^-1 nm^-1
};

// The disc, supersampled. For every pixel whose footprint the disc's cap can touch, k_u x
// k_v samples at the centres of a regular grid in (u, v) inside the pixel; a sample at
// elevation e stands for the solid angle cos(e) du dv (2 pi)(pi) of its cell. With
// rho the sample's angle from the disc centre, the pixel gathers
//     S(p, c) = sum over samples of LD_c(rho) dOmega,
// an estimate of the integral of the limb-darkening factor over the part of the disc in
// p, once over the whole disc (A_c) and once over its part above the horizon (V_c). The
// pixel's added radiance is then
//     L(p, c) = direct_irradiance_c * S_vis(p, c) / V_c / Omega_p,
// so that sum_p L(p, c) Omega_p = direct_irradiance_c exactly, whatever the sampling
// error of each S; the sampling only decides how that energy is shared between pixels.
// Sample spacing: at most alpha/8 in elevation and about alpha/8 in azimuth at the row's
// widest latitude, so the disc is resolved at any image size (capped at 256 x 256 per
// pixel for tiny images; if no sample lands on the visible disc, its energy goes to the
// pixel holding the disc's centre).
DiscSplat splat_sun_disc(const Atmosphere& atm, const Observer& obs, int width, int height,
                         const SunRadiometry& sun) {
    const std::size_t nc = atm.channels();
    const double alpha = atm.sun_angular_radius_rad;
    const glm::dvec3 s = obs.sun_direction;
    const double r = atm.bottom_radius_m + obs.altitude_m;
    const double e_s = std::asin(clamp_cosine(s.z));
    const double du_angle = kTwoPi / width, dv_angle = kPi / height;

    // Rows the cap can touch (one more each side for safety).
    const int j0 = std::max(0, int(std::floor((0.5 * kPi - (e_s + alpha)) / dv_angle)) - 1);
    const int j1 =
        std::min(height - 1, int(std::floor((0.5 * kPi - (e_s - alpha)) / dv_angle)) + 1);
    // Columns: all of them if the cap holds a pole; else the cap's azimuth half-width
    // asin(sin alpha / cos e_s) around the centre's column.
    int i0 = 0, ncols = width;
    if (e_s + alpha < 0.5 * kPi && e_s - alpha > -0.5 * kPi) {
        const double half = std::asin(std::min(1.0, std::sin(alpha) / std::cos(e_s)));
        const double u_c = direction_to_equirect(s).x;
        const int a = int(std::floor((u_c - half / kTwoPi) * width)) - 1;
        const int b = int(std::floor((u_c + half / kTwoPi) * width)) + 1;
        if (b - a + 1 < width) {
            i0 = a;
            ncols = b - a + 1;
        }
    }
    const int nrows = j1 - j0 + 1;

    std::vector<LimbDarkening> ld;
    for (double w : atm.wavelengths_nm) ld.emplace_back(alpha, w);

    const std::size_t npix = std::size_t(nrows) * std::size_t(ncols);
    std::vector<double> s_all(npix * nc, 0.0), s_vis(npix * nc, 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, npix), [&](const auto& range) {
        std::vector<double> ld_c(nc);
        for (std::size_t q = range.begin(); q != range.end(); ++q) {
            const int j = j0 + int(q / std::size_t(ncols));
            const int i = ((i0 + int(q % std::size_t(ncols))) % width + width) % width;
            // Widest latitude of the row: cos of the elevation closest to the equator.
            const double e_top = 0.5 * kPi - dv_angle * j, e_bot = e_top - dv_angle;
            const double cos_max = (e_top >= 0.0 && e_bot <= 0.0)
                                       ? 1.0
                                       : std::max(std::cos(e_top), std::cos(e_bot));
            const int kv = std::clamp(int(std::ceil(8.0 * dv_angle / alpha)), 2, 256);
            const int ku = std::clamp(int(std::ceil(8.0 * cos_max * du_angle / alpha)), 2, 256);
            const double cell = du_angle / ku * dv_angle / kv;
            double* all = &s_all[q * nc];
            double* vis = &s_vis[q * nc];
            for (int b = 0; b < kv; ++b) {
                const double e = e_top - dv_angle * (b + 0.5) / kv;
                const double ce = std::cos(e), se = std::sin(e);
                const bool visible = !ray_hits_ground(r, se, atm.bottom_radius_m);
                for (int a = 0; a < ku; ++a) {
                    const double phi = kPi - du_angle * (i + (a + 0.5) / ku);
                    const glm::dvec3 d{ce * std::cos(phi), ce * std::sin(phi), se};
                    const double rho =
                        std::atan2(glm::length(glm::cross(d, s)), glm::dot(d, s));
                    if (rho > alpha) continue;
                    const double w = ce * cell;
                    for (std::size_t c = 0; c < nc; ++c) {
                        const double v = ld[c](rho) * w;
                        all[c] += v;
                        if (visible) vis[c] += v;
                    }
                }
            }
        }
    });

    DiscSplat out;
    std::vector<double> visible_total(nc, 0.0);
    for (std::size_t q = 0; q < npix; ++q)
        for (std::size_t c = 0; c < nc; ++c) visible_total[c] += s_vis[q * nc + c];

    auto pixel_of = [&](int q) {
        const int j = j0 + q / ncols;
        const int i = ((i0 + q % ncols) % width + width) % width;
        return std::size_t(j) * std::size_t(width) + std::size_t(i);
    };
    for (std::size_t q = 0; q < npix; ++q) {
        bool any = false;
        for (std::size_t c = 0; c < nc; ++c) any = any || s_vis[q * nc + c] > 0.0;
        if (!any) continue;
        const int j = j0 + int(q / std::size_t(ncols));
        const double omega = equirect_pixel_solid_angle(j, width, height);
        out.pixel.push_back(pixel_of(int(q)));
        for (std::size_t c = 0; c < nc; ++c)
            out.radiance.push_back(visible_total[c] > 0.0 ? sun.direct_irradiance[c] *
                                                                s_vis[q * nc + c] /
                                                                visible_total[c] / omega
                                                          : 0.0);
    }
    // Channels whose visible disc no sample caught (a sliver at the horizon in a tiny
    // image): their energy goes to the pixel of the disc centre.
    for (std::size_t c = 0; c < nc; ++c) {
        if (visible_total[c] > 0.0 || !(sun.direct_irradiance[c] > 0.0)) continue;
        const glm::dvec2 uv = direction_to_equirect(s);
        const int i = std::min(width - 1, int(uv.x * width));
        const int j = std::clamp(int((1.0 - uv.y) * height), 0, height - 1);
        const std::size_t p = std::size_t(j) * std::size_t(width) + std::size_t(i);
        auto it = std::find(out.pixel.begin(), out.pixel.end(), p);
        std::size_t k = std::size_t(it - out.pixel.begin());
        if (it == out.pixel.end()) {
            out.pixel.push_back(p);
            out.radiance.resize(out.radiance.size() + nc, 0.0);
        }
        out.radiance[k * nc + c] +=
            sun.direct_irradiance[c] / equirect_pixel_solid_angle(j, width, height);
    }
    return out;
}

}  // namespace

void SkyImageOptions::validate() const {
    if (!(exposure > 0.0) || !(exposure <= 1e6))
        throw InvalidArgument("exposure", fmt::format("must be in (0, 1e6], got {}", exposure));
}

std::string spectral_channel_name(double wavelength_nm) {
    std::string number = fmt::format("{}", wavelength_nm);
    std::replace(number.begin(), number.end(), '.', ',');
    return "S0." + number + "nm";
}

SkyImage render_equirect_sky(const SkyMethod& method, const Atmosphere& atm,
                             const Observer& observer, int width,
                             const SkyImageOptions& options, Progress* progress) {
    options.validate();
    require_in_range("width", width, 4, 16384, "pixels");
    if (width % 2 != 0)
        throw InvalidArgument("width", fmt::format("must be even (height = width / 2), got {}",
                                                   width));
    atm.validate();
    const Observer obs = observer.validated();
    const bool rgb = options.output == SkyImageOptions::Output::Rgb;
    const std::size_t nc = atm.channels();
    // Conversions first: they reject unusable wavelengths before the expensive part.
    std::optional<SpectrumToRgb> sky_to_rgb, sun_to_rgb;
    if (rgb) {
        sky_to_rgb.emplace(atm.wavelengths_nm, -3.0);
        sun_to_rgb.emplace(atm.wavelengths_nm, 0.0);
    }

    SkyImage image;
    image.width = width;
    image.height = width / 2;
    const int W = image.width, H = image.height;
    if (rgb) {
        image.channel_names = {"R", "G", "B"};
    } else {
        image.wavelengths_nm = atm.wavelengths_nm;
        for (double w : atm.wavelengths_nm) image.channel_names.push_back(spectral_channel_name(w));
    }
    const std::size_t out_nc = image.channels();
    image.pixels.assign(std::size_t(W) * std::size_t(H) * out_nc, 0.0f);

    // Per-column and per-row factors of the pixel-centre directions (equirect.cpp):
    // direction = (cos e cos phi, cos e sin phi, sin e).
    std::vector<double> cos_phi(W), sin_phi(W), cos_e(H), sin_e(H);
    for (int i = 0; i < W; ++i) {
        const glm::dvec3 d = equirect_pixel_direction(i, H / 2, W, H);
        const double l = std::hypot(d.x, d.y);
        cos_phi[i] = d.x / l;
        sin_phi[i] = d.y / l;
    }
    for (int j = 0; j < H; ++j) {
        const glm::dvec3 d = equirect_pixel_direction(0, j, W, H);
        sin_e[j] = d.z;
        cos_e[j] = std::hypot(d.x, d.y);
    }

    // Sky radiance, in bands of rows (one band for all but very large images).
    const std::size_t row_values = std::size_t(W) * nc;
    const int band_rows = int(std::clamp<std::size_t>(kMaxValuesPerCall / row_values, 1,
                                                      std::size_t(H)));
    const int bands = (H + band_rows - 1) / band_rows;
    std::vector<glm::dvec3> directions(std::size_t(band_rows) * std::size_t(W));
    std::vector<float> radiance(std::size_t(band_rows) * row_values);
    for (int band = 0; band < bands; ++band) {
        const int row0 = band * band_rows;
        const int rows = std::min(band_rows, H - row0);
        const std::size_t n = std::size_t(rows) * std::size_t(W);
        tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const auto& range) {
            for (int jj = range.begin(); jj != range.end(); ++jj) {
                const int j = row0 + jj;
                glm::dvec3* row = &directions[std::size_t(jj) * std::size_t(W)];
                for (int i = 0; i < W; ++i)
                    row[i] = {cos_e[j] * cos_phi[i], cos_e[j] * sin_phi[i], sin_e[j]};
            }
        });
        SubProgress sub(progress, double(band) / bands, double(band + 1) / bands);
        const std::span<float> out(radiance.data(), n * nc);
        method.radiance(atm, obs, std::span<const glm::dvec3>(directions.data(), n), out, {},
                        progress ? &sub : nullptr);

        const std::size_t bad = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, out.size(), 1 << 16), std::size_t(-1),
            [&](const auto& range, std::size_t first) {
                for (std::size_t k = range.begin(); k != range.end() && first == std::size_t(-1);
                     ++k)
                    if (!std::isfinite(out[k])) first = k;
                return first;
            },
            [](std::size_t a, std::size_t b) { return std::min(a, b); });
        if (bad != std::size_t(-1)) {
            const std::size_t k = bad / nc;
            const glm::dvec3 d = directions[k];
            throw std::runtime_error(fmt::format(
                "sky method '{}' returned a non-finite radiance ({}) for direction "
                "({:.6f}, {:.6f}, {:.6f})",
                method.name(), out[bad], d.x, d.y, d.z));
        }

        float* dst = image.pixels.data() + std::size_t(row0) * std::size_t(W) * out_nc;
        if (rgb)
            sky_to_rgb->convert(out, std::span<float>(dst, n * 3));
        else
            std::copy(out.begin(), out.end(), dst);
    }

    if (options.sun_disc) {
        const SunRadiometry sun = sun_radiometry(atm, obs);
        if (sun.visible_fraction > 0.0) {
            const DiscSplat disc = splat_sun_disc(atm, obs, W, H, sun);
            std::vector<float> spectrum(nc);
            for (std::size_t k = 0; k < disc.pixel.size(); ++k) {
                float* dst = image.pixels.data() + disc.pixel[k] * out_nc;
                for (std::size_t c = 0; c < nc; ++c) spectrum[c] = float(disc.radiance[k * nc + c]);
                if (rgb) {
                    const std::array<double, 3> add = sun_to_rgb->convert(spectrum);
                    for (int c = 0; c < 3; ++c) dst[c] = float(double(dst[c]) + add[c]);
                } else {
                    for (std::size_t c = 0; c < nc; ++c) dst[c] += spectrum[c];
                }
            }
        }
    }

    if (options.exposure != 1.0) {
        const float e = float(options.exposure);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, image.pixels.size(), 1 << 16),
                          [&](const auto& range) {
                              for (std::size_t k = range.begin(); k != range.end(); ++k)
                                  image.pixels[k] *= e;
                          });
    }
    if (progress) progress->report(1.0);
    return image;
}

}  // namespace welkin
