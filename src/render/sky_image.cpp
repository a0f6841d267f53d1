// SPDX-License-Identifier: Apache-2.0
// Equirectangular sky images with the sun's disc; see sky_image.hpp.
#include "welkin/render/sky_image.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <sys/mman.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/ground.hpp"
#include "welkin/atmosphere/sun_disc.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/gamut.hpp"

namespace welkin {
namespace {

// Radiance values held at once: the method is called with every pixel of the image when
// (pixels x channels) fits in this many floats (512 MiB: any 3-channel image up to 8192
// wide, a 48-channel spectral one up to 2048 wide), else with bands of whole rows, so that
// the spectral mode at large sizes does not need gigabytes. Bands cost: the lut method
// builds its tables once per call (~1.2 s at 48 wavelengths on two cores).
constexpr std::size_t kMaxValuesPerCall = std::size_t(128) << 20;

// Large scratch buffers: 2 MiB aligned and marked for transparent huge pages, where the
// kernel allows them (Linux, THP in "madvise" or "always" mode). First-touch page faults
// of 4 KiB pages dominated the image assembly at 2048 x 1024 (48 MiB of directions);
// huge pages cut their number 512-fold. Elsewhere this is a plain aligned allocation.
constexpr std::size_t kHugePage = std::size_t(2) << 20;
struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
};
template <class T>
std::unique_ptr<T[], FreeDeleter> huge_buffer(std::size_t n) {
    const std::size_t pages = std::max<std::size_t>(1, (n * sizeof(T) + kHugePage - 1) / kHugePage);
    const std::size_t bytes = pages * kHugePage;
    void* p = std::aligned_alloc(kHugePage, bytes);
    if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    ::madvise(p, bytes, MADV_HUGEPAGE);
#endif
    return std::unique_ptr<T[], FreeDeleter>(static_cast<T*>(p));
}

// The image's own vector: reserved first, so that the same advice applies before resize()
// touches (zeroes) its pages.
void advise_huge_pages(std::vector<float>& v, std::size_t n) {
    v.reserve(n);
#ifdef MADV_HUGEPAGE
    const std::uintptr_t begin = reinterpret_cast<std::uintptr_t>(v.data());
    const std::uintptr_t end = begin + n * sizeof(float);
    const std::uintptr_t a = (begin + kHugePage - 1) / kHugePage * kHugePage;
    if (end > a + kHugePage)
        ::madvise(reinterpret_cast<void*>(a), (end - a) / kHugePage * kHugePage, MADV_HUGEPAGE);
#endif
}

// Adds the sun's disc to `pixels` (height x width x channels, top row first): spectral
// radiance per atmosphere wavelength in `disc` (the caller converts it), keyed by pixel.
struct DiscSplat {
    std::vector<std::size_t> pixel;  // index y * width + x
    std::vector<double> radiance;    // (pixel.size(), channels), W m^-2 sr^-1 nm^-1
};

// The disc, supersampled. For every pixel that the disc's cap can touch, a regular grid
// of samples over the part of the pixel inside the cap's bounding box (u, v); a sample at
// elevation e stands for the solid angle cos(e) dphi de of its cell. With L_c(rho) the
// disc's radiance (sun_disc.hpp) at the sample's angle rho from the disc centre, the
// pixel gathers
//     S(p, c) = sum over samples above the horizon of L_c(rho) dOmega,
// an estimate of the disc's irradiance from the visible part of the disc inside p. With
// V_c = sum_p S(p, c), the pixel's added radiance is
//     L(p, c) = direct_irradiance_c * S(p, c) / V_c / Omega_p,
// so that sum_p L(p, c) Omega_p = direct_irradiance_c exactly, whatever the sampling
// error of each S: the sampling only decides how that energy is shared between pixels,
// and pixels the disc covers partly get a partial (antialiased) value. Sample spacing:
// at most alpha / 8, so the disc is resolved at any image size. If no sample lands on the
// visible disc (a sliver at the horizon), its energy goes to the pixel of its centre.
DiscSplat splat_sun_disc(const Atmosphere& atm, const Observer& obs, int width, int height,
                         const SunDisc& disc) {
    const std::size_t nc = atm.channels();
    const SunRadiometry& sun = disc.radiometry();
    const double alpha = disc.angular_radius_rad();
    const glm::dvec3 s = disc.direction();
    const double r = atm.bottom_radius_m + obs.altitude_m;
    const double e_s = std::asin(clamp_cosine(s.z));
    const double dv_angle = kPi / height;

    // The cap's bounding box: elevations [e_s - alpha, e_s + alpha]; in u, the centre's u
    // plus or minus the cap's azimuth half-width asin(sin alpha / cos e_s) / (2 pi), or
    // every u when the cap holds a pole.
    const double e_lo = e_s - alpha, e_hi = e_s + alpha;
    const int j0 = std::max(0, int(std::floor((0.5 * kPi - e_hi) / dv_angle)));
    const int j1 = std::min(height - 1, int(std::floor((0.5 * kPi - e_lo) / dv_angle)));
    bool all_u = true;
    double u_lo = 0.0, u_hi = 1.0;
    int i0 = 0, ncols = width;
    if (e_hi < 0.5 * kPi && e_lo > -0.5 * kPi) {
        const double half = std::asin(std::min(1.0, std::sin(alpha) / std::cos(e_s))) / kTwoPi;
        const double u_c = direction_to_equirect(s).x;
        const int a = int(std::floor((u_c - half) * width));
        const int b = int(std::floor((u_c + half) * width));
        if (b - a + 1 < width) {
            all_u = false;
            u_lo = u_c - half;
            u_hi = u_c + half;
            i0 = a;
            ncols = b - a + 1;
        }
    }
    const int nrows = j1 - j0 + 1;

    // Each pixel samples only its intersection with the box, on a grid of spacing at most
    // alpha / 8 in elevation and in azimuth (at the latitude where the intersection is
    // widest): the cost follows the disc's size, not the pixel's.
    const std::size_t npix = std::size_t(nrows) * std::size_t(ncols);
    std::vector<double> s_vis(npix * nc, 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, npix), [&](const auto& range) {
        for (std::size_t q = range.begin(); q != range.end(); ++q) {
            const int j = j0 + int(q / std::size_t(ncols));
            const int ii = i0 + int(q % std::size_t(ncols));  // may lie outside [0, width)
            // Elevation and u extent of pixel (ii, j) intersected with the box.
            const double e_top = std::min(0.5 * kPi - dv_angle * j, e_hi);
            const double e_bot = std::max(0.5 * kPi - dv_angle * (j + 1), e_lo);
            const double pu0 = double(ii) / width, pu1 = double(ii + 1) / width;
            const double u0 = all_u ? pu0 : std::max(pu0, u_lo);
            const double u1 = all_u ? pu1 : std::min(pu1, u_hi);
            if (!(e_top > e_bot) || !(u1 > u0)) continue;
            const double cos_max =
                (e_top >= 0.0 && e_bot <= 0.0) ? 1.0 : std::max(std::cos(e_top), std::cos(e_bot));
            const double de = e_top - e_bot, dphi = kTwoPi * (u1 - u0);
            const int kv = std::clamp(int(std::ceil(8.0 * de / alpha)), 2, 512);
            const int ku = std::clamp(int(std::ceil(8.0 * cos_max * dphi / alpha)), 2, 512);
            const double cell = dphi / ku * de / kv;
            double* vis = &s_vis[q * nc];
            for (int b = 0; b < kv; ++b) {
                const double e = e_top - de * (b + 0.5) / kv;
                const double ce = std::cos(e), se = std::sin(e);
                if (ray_hits_ground(r, se, atm.bottom_radius_m)) continue;  // behind the ground
                for (int a = 0; a < ku; ++a) {
                    const double phi = kPi - kTwoPi * (u0 + (u1 - u0) * (a + 0.5) / ku);
                    const glm::dvec3 d{ce * std::cos(phi), ce * std::sin(phi), se};
                    disc.add_radiance(disc.angle_to(d), ce * cell, std::span<double>(vis, nc));
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
            out.radiance.push_back(visible_total[c] > 0.0 ? sun.direct_irradiance[c] * s_vis[q * nc + c] /
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
        out.radiance[k * nc + c] += sun.direct_irradiance[c] / equirect_pixel_solid_angle(j, width, height);
    }
    return out;
}

// The steps of render_equirect_sky, in order.

// 1. The image: its size, channel names and zeroed pixels.
SkyImage make_image(const Atmosphere& atm, int width, bool rgb) {
    SkyImage image;
    image.width = width;
    image.height = width / 2;
    if (rgb) {
        image.channel_names = {"R", "G", "B"};
    } else {
        image.wavelengths_nm = atm.wavelengths_nm;
        for (double w : atm.wavelengths_nm) image.channel_names.push_back(spectral_channel_name(w));
    }
    const std::size_t n = std::size_t(image.width) * std::size_t(image.height) * image.channels();
    advise_huge_pages(image.pixels, n);
    image.pixels.resize(n, 0.0f);
    return image;
}

// 2. The pixel-centre directions, from per-column and per-row factors (equirect.cpp):
// direction = (cos e cos phi, cos e sin phi, sin e).
class PixelDirections {
public:
    PixelDirections(int width, int height)
        : width_(width), cos_phi_(width), sin_phi_(width), cos_e_(height), sin_e_(height) {
        for (int i = 0; i < width; ++i) {
            const glm::dvec3 d = equirect_pixel_direction(i, height / 2, width, height);
            const double l = std::hypot(d.x, d.y);
            cos_phi_[i] = d.x / l;
            sin_phi_[i] = d.y / l;
        }
        for (int j = 0; j < height; ++j) {
            const glm::dvec3 d = equirect_pixel_direction(0, j, width, height);
            sin_e_[j] = d.z;
            cos_e_[j] = std::hypot(d.x, d.y);
        }
    }
    // Rows [row0, row0 + rows) into out (rows x width), in parallel (first touch).
    void fill(int row0, int rows, glm::dvec3* out) const {
        tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const auto& range) {
            for (int jj = range.begin(); jj != range.end(); ++jj) {
                const int j = row0 + jj;
                glm::dvec3* row = out + std::size_t(jj) * std::size_t(width_);
                for (int i = 0; i < width_; ++i)
                    row[i] = {cos_e_[j] * cos_phi_[i], cos_e_[j] * sin_phi_[i], sin_e_[j]};
            }
        });
    }

private:
    int width_;
    std::vector<double> cos_phi_, sin_phi_, cos_e_, sin_e_;
};

// 3. The lit ground (header, "The ground") on the views of a band that meet it, added to
// the method's path radiance `sky` (n x nc) of those views, for a sun in `sun` (each sun
// of render_equirect_sky's shares the rows' geometry).
class GroundShading {
public:
    GroundShading(const Atmosphere& atm, const Observer& obs, const std::optional<double>& albedo, int height)
        : light_(GroundIllumination::shared(atm)),
          nc_(atm.channels()),
          r_(atm.bottom_radius_m + obs.altitude_m),
          rows_(height) {
        for (std::size_t c = 0; c < nc_; ++c)
            albedo_over_pi_.push_back((albedo ? *albedo : atm.ground_albedo[c]) / kPi);
        const double R = atm.bottom_radius_m;
        const int W = 2 * height;
        // Per row: whether its views meet the ground, the distance, the transmittance.
        for (int j = 0; j < height; ++j) {
            const double mu = equirect_pixel_direction(0, j, W, height).z;
            Row& row = rows_[std::size_t(j)];
            if (!ray_hits_ground(r_, mu, R)) continue;
            row.distance = distance_to_bottom(r_, mu, R);
            row.transmittance = transmittance_along(atm, r_, mu, row.distance);
            row.hits = true;
        }
    }

    void add(int row0, int rows, int width, const glm::dvec3* dirs, const glm::dvec3& sun, float* sky) const {
        tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const auto& range) {
            std::vector<double> e(nc_);
            for (int jj = range.begin(); jj != range.end(); ++jj) {
                const Row& row = rows_[std::size_t(row0 + jj)];
                if (!row.hits) continue;
                if (row.distance == 0.0) {
                    // The observer on the ground: every view of the row meets it at the
                    // observer's own point, p = x, one irradiance for the row.
                    const glm::dvec3 p(0.0, 0.0, r_);
                    light_->irradiance(glm::dot(p, sun) / glm::length(p), e);
                    for (std::size_t c = 0; c < nc_; ++c)
                        e[c] = row.transmittance[c] * albedo_over_pi_[c] * e[c];
                    for (int i = 0; i < width; ++i) {
                        float* L = sky + (std::size_t(jj) * std::size_t(width) + std::size_t(i)) * nc_;
                        for (std::size_t c = 0; c < nc_; ++c) L[c] += float(e[c]);
                    }
                    continue;
                }
                for (int i = 0; i < width; ++i) {
                    const std::size_t q = std::size_t(jj) * std::size_t(width) + std::size_t(i);
                    // The ground point p = x + d v, x = (0, 0, r); mu_s = (p / |p|) . s.
                    const glm::dvec3 p = glm::dvec3(0.0, 0.0, r_) + row.distance * dirs[q];
                    light_->irradiance(glm::dot(p, sun) / glm::length(p), e);
                    float* L = sky + q * nc_;
                    for (std::size_t c = 0; c < nc_; ++c)
                        L[c] += float(row.transmittance[c] * albedo_over_pi_[c] * e[c]);
                }
            }
        });
    }

private:
    struct Row {
        bool hits = false;
        double distance = 0.0;
        std::vector<double> transmittance;
    };
    std::shared_ptr<const GroundIllumination> light_;  // shared by every image of this atmosphere
    std::size_t nc_;
    double r_;
    std::vector<double> albedo_over_pi_;
    std::vector<Row> rows_;
};

// 4. The clouds of one band of rows: the march through the density, and the air between
// the observer and each cloud (header, "Clouds"), combined into the cloud's term of the
// composite, T(0, d_c) L_c + (1 - T_c) S(0, d_c). Rays the upsampling interpolated
// (render_clouds_grid) get that term interpolated from the same corner rays: the air is
// marched for the marched rays only.
struct BandClouds {
    CloudResult march;
    std::vector<float> cloud;  // (n, 3) in Rec.709 for RGB output, else (n, nc)
};
BandClouds march_band_clouds(const SkyImageOptions& options, const AtmosphereIllumination& light,
                             const Atmosphere& atm, const Observer& obs, std::span<const glm::dvec3> dirs,
                             int width, std::uint64_t first_pixel, const SpectrumToRgb* sky_to_rgb,
                             Progress* progress) {
    BandClouds b;
    const std::size_t n = dirs.size(), nc = atm.channels();
    // The rays' footprint (lighting.hpp), unless set: the angle between neighbouring
    // pixels, 2 pi / width (a column's rows and the horizon's columns; the rows' columns
    // draw closer towards the poles).
    CloudLightingOptions lighting = options.cloud_lighting;
    if (lighting.ray_spread_rad == 0.0 && lighting.ray_width_m == 0.0)
        lighting.ray_spread_rad = std::min(1.0, kTwoPi / double(width));
    b.march = render_clouds_grid(*options.clouds, light, glm::dvec3(0.0), dirs, width, lighting,
                                 options.cloud_upsampling, progress, first_pixel);
    const CloudGridInterpolation& grid = b.march.interpolation;
    std::vector<double> cloud_d(n, 0.0);  // 0: no cloud, or not marched
    for (std::size_t q = 0; q < n; ++q)
        if (b.march.transmittance[q] < 1.0f && grid.was_marched(q)) cloud_d[q] = double(b.march.depth_m[q]);
    const glm::dvec3 origin(0.0);
    const AirAlongRays air =
        aerial_along_rays(atm, light.luts(), {0.0, 0.0, -(atm.bottom_radius_m + obs.altitude_m)},
                          obs.sun_direction, std::span<const glm::dvec3>(&origin, 1), dirs, cloud_d,
                          options.air_steps, 1.0, sky_to_rgb == nullptr, options.color_space);
    const std::size_t m = sky_to_rgb ? 3 : nc;
    b.cloud.resize(n * m);
    if (sky_to_rgb) {
        // As the passes take it: the air's RGB transmittance times the RGB cloud radiance.
        sky_to_rgb->convert(b.march.radiance, b.cloud);
        for (std::size_t q = 0; q < n; ++q)
            for (std::size_t k = 0; k < 3; ++k)
                b.cloud[q * 3 + k] = air.transmittance[q * 3 + k] * b.cloud[q * 3 + k] +
                                     (1.0f - b.march.transmittance[q]) * air.inscatter[q * 3 + k];
    } else {
        for (std::size_t q = 0; q < n; ++q)
            for (std::size_t c = 0; c < nc; ++c)
                b.cloud[q * nc + c] = air.transmittance_spectral[q * nc + c] * b.march.radiance[q * nc + c] +
                                      (1.0f - b.march.transmittance[q]) * air.inscatter_spectral[q * nc + c];
    }
    grid.interpolate(b.cloud, m);
    return b;
}

// One spectrum and its RGB output (composite_and_convert).
struct Memo {
    explicit Memo(std::size_t nc) : spectrum(nc) {}
    std::vector<float> spectrum;
    float rgb[3] = {0.0f, 0.0f, 0.0f};
    bool valid = false;
    bool same(const float* v) const {  // bit for bit (-0 and 0 apart)
        return valid && std::memcmp(spectrum.data(), v, spectrum.size() * sizeof(float)) == 0;
    }
    void keep(const float* v) {
        std::copy_n(v, spectrum.size(), spectrum.begin());
        valid = true;
    }
};

// The radiance of one band for an extra sun (n x nc), and its scale.
struct ExtraBand {
    const float* sky;
    float scale;
};

// 5. One band's output pixels from its sky radiance `sky` (n x nc): the clouds composited
// over it (header), then, for RGB output, the conversion into `dst` (n x 3; `dst` may be
// `sky` itself when nc == 3: each pixel is read before it is written); plus each extra
// sun's radiance times its scale (no clouds then), converted and brought into the gamut
// on its own. Returns the index of the first pixel with a non-finite radiance, or npos.
constexpr std::size_t kNone = std::size_t(-1);
std::size_t composite_and_convert(float* sky, float* dst, std::size_t n, std::size_t nc,
                                  const SpectrumToRgb* to_rgb, const BandClouds* clouds,
                                  std::span<const ExtraBand> extra) {
    const bool rgb = to_rgb != nullptr;
    const std::vector<double> m = rgb ? to_rgb->matrix() : std::vector<double>{};
    std::atomic<std::size_t> bad{kNone};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& range) {
        std::array<double, 9> m3{};  // local copy: no reloads through possible aliases
        if (rgb && nc == 3) std::copy(m.begin(), m.end(), m3.begin());
        std::size_t first = kNone;
        // The last spectrum converted (per sun) and its RGB, brought into the gamut: a run
        // of equal spectra (the ground's rows seen from the ground are one spectrum each)
        // is converted once, with the same result.
        std::vector<Memo> memo(rgb && !clouds ? 1 + extra.size() : 0, Memo(nc));
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            float* s = &sky[i * nc];
            // The sky behind the cloud: T_c L_sky; with spectral output also the cloud's
            // term (its own light through the air and the air in front of it, header).
            const float T = clouds ? clouds->march.transmittance[i] : 1.0f;
            if (clouds) {
                if (rgb) {
                    for (std::size_t c = 0; c < nc; ++c) s[c] *= T;
                } else {
                    const float* Lc = &clouds->cloud[i * nc];
                    for (std::size_t c = 0; c < nc; ++c) s[c] = s[c] * T + Lc[c];
                }
            }
            bool finite = true;
            for (std::size_t c = 0; c < nc; ++c) finite = finite && std::isfinite(s[c]);
            for (const ExtraBand& x : extra)
                for (std::size_t c = 0; c < nc; ++c) finite = finite && std::isfinite(x.sky[i * nc + c]);
            if (!finite && first == kNone) first = i;
            if (!rgb) {
                for (const ExtraBand& x : extra)
                    for (std::size_t c = 0; c < nc; ++c) s[c] += x.scale * x.sky[i * nc + c];
                continue;
            }
            // One spectrum into RGB (possibly in place when nc == 3).
            auto convert = [&](const float* v, float* d) {
                if (nc == 3) {
                    const float a = v[0], b = v[1], c = v[2];
                    d[0] = float(m3[0] * a + m3[1] * b + m3[2] * c);
                    d[1] = float(m3[3] * a + m3[4] * b + m3[5] * c);
                    d[2] = float(m3[6] * a + m3[7] * b + m3[8] * c);
                } else {
                    double r = 0.0, g = 0.0, b = 0.0;
                    for (std::size_t c = 0; c < nc; ++c) {
                        r += m[c] * v[c];
                        g += m[nc + c] * v[c];
                        b += m[2 * nc + c] * v[c];
                    }
                    d[0] = float(r), d[1] = float(g), d[2] = float(b);
                }
            };
            float* d = &dst[3 * i];
            if (!memo.empty() && memo[0].same(s)) {
                std::copy_n(memo[0].rgb, 3, d);
            } else {
                if (!memo.empty()) memo[0].keep(s);
                convert(s, d);
                // RGB output: the cloud's term in Rec.709, as the passes' Welkin.Clouds.rgb.
                if (clouds)
                    for (int k = 0; k < 3; ++k) d[k] += clouds->cloud[i * 3 + k];
                if (d[0] < 0.0f || d[1] < 0.0f || d[2] < 0.0f)  // into the output space's gamut (gamut.hpp)
                    gamut_map(d, 1, to_rgb->luminance_weights());
                if (!memo.empty()) std::copy_n(d, 3, memo[0].rgb);
            }
            for (std::size_t x = 0; x < extra.size(); ++x) {
                const float* v = &extra[x].sky[i * nc];
                Memo& e = memo[1 + x];
                if (!e.same(v)) {
                    e.keep(v);
                    convert(v, e.rgb);
                    if (e.rgb[0] < 0.0f || e.rgb[1] < 0.0f || e.rgb[2] < 0.0f)
                        gamut_map(e.rgb, 1, to_rgb->luminance_weights());
                }
                for (int k = 0; k < 3; ++k) d[k] += extra[x].scale * e.rgb[k];
            }
        }
        std::size_t cur = bad.load();
        while (first < cur && !bad.compare_exchange_weak(cur, first)) {
        }
    });
    return bad.load();
}

// 6. The sun's disc (sun_disc.hpp, splat_sun_disc), dimmed by the clouds' transmittance of
// its pixels when there are clouds.
void add_sun_disc(SkyImage& image, const Atmosphere& atm, const Observer& obs,
                  const SpectrumToRgb* sun_to_rgb, const std::vector<float>& cloud_transmittance) {
    const SunDisc sun(atm, obs);
    if (!(sun.radiometry().visible_fraction > 0.0)) return;
    const std::size_t nc = atm.channels(), out_nc = image.channels();
    const DiscSplat disc = splat_sun_disc(atm, obs, image.width, image.height, sun);
    std::vector<float> spectrum(nc);
    for (std::size_t k = 0; k < disc.pixel.size(); ++k) {
        float* dst = image.pixels.data() + disc.pixel[k] * out_nc;
        const float T = cloud_transmittance.empty() ? 1.0f : cloud_transmittance[disc.pixel[k]];
        for (std::size_t c = 0; c < nc; ++c) spectrum[c] = float(disc.radiance[k * nc + c]) * T;
        if (sun_to_rgb) {
            const std::array<double, 3> add = sun_to_rgb->convert(spectrum);
            for (int c = 0; c < 3; ++c) dst[c] = float(double(dst[c]) + add[c]);
        } else {
            for (std::size_t c = 0; c < nc; ++c) dst[c] += spectrum[c];
        }
    }
}

// 7. The exposure, once, at the end.
void apply_exposure(std::vector<float>& pixels, double exposure) {
    if (exposure == 1.0) return;
    const float e = float(exposure);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pixels.size(), 1 << 16), [&](const auto& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) pixels[k] *= e;
    });
}

}  // namespace

void SkyImageOptions::validate() const {
    if (!(exposure > 0.0) || !(exposure <= 1e6))
        throw InvalidArgument("exposure", fmt::format("must be in (0, 1e6], got {}", exposure));
    if (clouds) cloud_lighting.validate();
    require_in_range("air_steps", air_steps, 1, 4096);
    if (ground_albedo) require_in_range("ground_albedo", *ground_albedo, 0.0, 1.0);
}

std::string spectral_channel_name(double wavelength_nm) {
    std::string number = fmt::format("{}", wavelength_nm);
    std::replace(number.begin(), number.end(), '.', ',');
    return "S0." + number + "nm";
}

SkyImage render_equirect_sky(const SkyMethod& method, const Atmosphere& atm, const Observer& observer,
                             int width, const SkyImageOptions& options, Progress* progress) {
    return render_equirect_sky(method, atm, observer, {}, width, options, progress);
}

SkyImage render_equirect_sky(const SkyMethod& method, const Atmosphere& atm, const Observer& observer,
                             std::span<const ExtraSun> extra, int width, const SkyImageOptions& options,
                             Progress* progress) {
    options.validate();
    std::vector<Observer> extra_obs;  // each extra sun as the observer's sun
    for (const ExtraSun& x : extra) {
        const glm::dvec3& v = x.direction;
        if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) ||
            (v.x == 0.0 && v.y == 0.0 && v.z == 0.0))
            throw InvalidArgument("extra_suns", "each direction must be a finite non-zero vector");
        if (!(x.irradiance_scale >= 0.0) || !std::isfinite(x.irradiance_scale))
            throw InvalidArgument(
                "extra_suns",
                fmt::format("irradiance_scale must be finite and >= 0, got {}", x.irradiance_scale));
        if (options.clouds)
            throw InvalidArgument("extra_suns", "not with clouds (they would be lit by the first sun alone)");
        Observer o = observer;
        o.sun_direction = v;
        extra_obs.push_back(o.validated());
    }
    require_in_range("width", width, 4, 16384, "pixels");
    if (width % 2 != 0)
        throw InvalidArgument("width", fmt::format("must be even (height = width / 2), got {}", width));
    atm.validate();
    const Observer obs = observer.validated();
    const bool rgb = options.output == SkyImageOptions::Output::Rgb;
    const std::size_t nc = atm.channels();
    // Conversions first: they reject unusable wavelengths before the expensive part.
    std::optional<SpectrumToRgb> sky_to_rgb, sun_to_rgb;
    if (rgb) {
        sky_to_rgb.emplace(atm.wavelengths_nm, -3.0, options.color_space);
        sun_to_rgb.emplace(atm.wavelengths_nm, 0.0, options.color_space);
    }

    SkyImage image = make_image(atm, width, rgb);
    const int W = image.width, H = image.height;
    const std::size_t out_nc = image.channels();
    const PixelDirections pixel_directions(W, H);

    // Sky radiance, in bands of rows (one band for all but very large images). Where the
    // method's output has the image's layout (spectral output, or three wavelengths to
    // RGB) it writes straight into the image and is converted in place; otherwise into a
    // scratch band. Scratch buffers are left uninitialised and first touched by the
    // parallel loops that fill them: at 2048 x 1024, zeroing them serially cost more than
    // everything else here.
    const std::size_t row_values = std::size_t(W) * nc;
    const int band_rows = int(std::clamp<std::size_t>(kMaxValuesPerCall / row_values, 1, std::size_t(H)));
    const int bands = (H + band_rows - 1) / band_rows;
    const bool in_place = !rgb || nc == 3;
    const std::size_t band_pixels = std::size_t(band_rows) * std::size_t(W);
    const auto directions = huge_buffer<glm::dvec3>(band_pixels);
    const auto scratch = huge_buffer<float>(in_place ? 0 : band_pixels * nc);
    std::vector<std::unique_ptr<float[], FreeDeleter>> extra_scratch;
    for (std::size_t k = 0; k < extra.size(); ++k)
        extra_scratch.push_back(huge_buffer<float>(band_pixels * nc));
    std::optional<GroundShading> ground;
    if (options.ground) ground.emplace(atm, obs, options.ground_albedo, H);
    // Clouds: the illumination is built once; the cloud transmittance of every pixel is
    // kept for the sun's disc.
    std::unique_ptr<AtmosphereIllumination> cloud_light;
    std::vector<float> cloud_transmittance;
    if (options.clouds) {
        cloud_light = std::make_unique<AtmosphereIllumination>(atm, obs);
        cloud_transmittance.assign(std::size_t(W) * std::size_t(H), 1.0f);
    }
    for (int band = 0; band < bands; ++band) {
        const int row0 = band * band_rows;
        const int rows = std::min(band_rows, H - row0);
        const std::size_t n = std::size_t(rows) * std::size_t(W);
        pixel_directions.fill(row0, rows, directions.get());
        const std::span<const glm::dvec3> dirs(directions.get(), n);
        // The band's progress, shared by its suns' radiance calls.
        const double parts = double(1 + extra.size()), f0 = double(band) / bands,
                     f1 = double(band + 1) / bands;
        ProgressStage stage(progress, f0, f0 + (f1 - f0) / parts);
        Progress* band_progress = progress ? &stage : nullptr;
        float* dst = image.pixels.data() + std::size_t(row0) * std::size_t(W) * out_nc;
        float* sky = in_place ? dst : scratch.get();
        method.radiance(atm, obs, dirs, std::span<float>(sky, n * nc), {}, band_progress);
        if (ground) ground->add(row0, rows, W, directions.get(), obs.sun_direction, sky);
        std::vector<ExtraBand> extra_bands;
        for (std::size_t k = 0; k < extra.size(); ++k) {
            ProgressStage part(progress, f0 + (f1 - f0) * double(k + 1) / parts,
                               f0 + (f1 - f0) * double(k + 2) / parts);
            float* x = extra_scratch[k].get();
            method.radiance(atm, extra_obs[k], dirs, std::span<float>(x, n * nc), {},
                            progress ? &part : nullptr);
            if (ground) ground->add(row0, rows, W, directions.get(), extra_obs[k].sun_direction, x);
            extra_bands.push_back({x, float(extra[k].irradiance_scale)});
        }
        std::optional<BandClouds> clouds;
        if (options.clouds) {
            clouds = march_band_clouds(options, *cloud_light, atm, obs, dirs, W,
                                       std::uint64_t(row0) * std::uint64_t(W), rgb ? &*sky_to_rgb : nullptr,
                                       band_progress);
            std::copy(clouds->march.transmittance.begin(), clouds->march.transmittance.end(),
                      cloud_transmittance.begin() + std::ptrdiff_t(row0) * W);
        }
        const std::size_t bad = composite_and_convert(sky, dst, n, nc, rgb ? &*sky_to_rgb : nullptr,
                                                      clouds ? &*clouds : nullptr, extra_bands);
        if (bad != kNone) {
            const glm::dvec3 d = directions[bad];
            throw std::runtime_error(
                fmt::format("sky method '{}' returned a non-finite radiance for direction "
                            "({:.6f}, {:.6f}, {:.6f})",
                            method.name(), d.x, d.y, d.z));
        }
    }

    if (options.sun_disc) add_sun_disc(image, atm, obs, rgb ? &*sun_to_rgb : nullptr, cloud_transmittance);
    image.cloud_transmittance = std::move(cloud_transmittance);
    apply_exposure(image.pixels, options.exposure);
    if (progress) progress->report(1.0);
    return image;
}

}  // namespace welkin
