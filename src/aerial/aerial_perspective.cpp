// SPDX-License-Identifier: Apache-2.0
// Aerial perspective: Hillaire 2020's camera volume and the per-pixel march; see
// aerial_perspective.hpp for what the passes mean.
//
// Both ways integrate the same thing along a ray x(t) = p0 + t d (p0 relative to the
// planet centre, double precision, so r - R stays exact to well below a millimetre):
// the segment [t0, t1] is cut into n equal steps, each sampled at its midpoint, and
// each step adds, in Hillaire's energy-conserving form (Hillaire 2015, "Physically
// Based and Unified Volumetric Rendering in Frostbite", sec. 5.6.3; also
// inscattering.hpp),
//     L += T S (1 - exp(-sigma_t dt)) / sigma_t,      T *= exp(-sigma_t dt),
// with the source S = T_sun (sigma_R P_R(nu) + sigma_M P_M(nu)) + (sigma_R + sigma_M) Psi_ms
// (Hillaire 2020 eqs. 1-4, 10; times E_sun at the end). The form is exact for a
// constant source in a homogeneous step however optically thick the step is, which is
// what keeps deep slices in strong haze from banding. The sun's direction is the same
// at every point (the sun is at infinity), so its zenith cosine at x is dot(x, s) / |x|;
// T_sun (with the planet's shadow) and Psi_ms are lookups in the atmosphere's LUTs.
#include "welkin/aerial/aerial_perspective.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "air_march.hpp"
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/base/memory.hpp"

namespace welkin {

using aerial_march::air_ray;
using aerial_march::AirRay;
using aerial_march::march_grid;
using aerial_march::march_segment;
using aerial_march::optical_depth_of;
using aerial_march::PassColour;

namespace {

// The part of [0, t_end] of the ray inside the atmosphere's top sphere; empty when the
// ray misses it.
bool clip_to_atmosphere(const AirRay& ray, double top, double t_end, double& t0, double& t1) {
    const double r = glm::length(ray.p0);
    const double rmu = glm::dot(ray.p0, ray.d);
    const double disc = rmu * rmu - (r - top) * (r + top);
    if (disc < 0.0) return false;
    const double q = std::sqrt(disc);
    t0 = std::max(0.0, -rmu - q);
    t1 = std::min(t_end, -rmu + q);
    return t1 > t0;
}

// One ray's spectral air over [0, t_end] (L with E_sun, T; all channels): false, with L
// and T untouched, when the ray misses the atmosphere.
bool march_ray(const AtmosphereLuts& luts, const AirRay& ray, double top, double t_end, int steps, float* L,
               float* T) {
    double t0, t1;
    if (!clip_to_atmosphere(ray, top, t_end, t0, t1)) return false;
    const float nu = float(clamp_cosine(glm::dot(ray.d, ray.sun)));
    for (const auto& b : luts.batches()) {
        Spectrum4 Ls(0.0f), Ts(1.0f);
        march_segment(*b, ray, b->medium.rayleigh_phase(nu), b->medium.mie_phase(nu), t0, t1, steps, Ls, Ts);
        store_channels(Ls * b->medium.solar_irradiance(), b->medium.channel_count(),
                       L + b->medium.first_channel());
        store_channels(Ts, b->medium.channel_count(), T + b->medium.first_channel());
    }
    return true;
}

void check_call(const AerialView& view, std::span<const float> depth, int width, int height) {
    view.validate();
    if (width != view.width || height != view.height)
        throw InvalidArgument("depth", fmt::format("is {} x {} pixels but the camera renders {} x {}", width,
                                                   height, view.width, view.height));
    check_frame_memory(width, height, kAerialPassBytesPerPixel, "depth and aerial passes (float)");
    validate_depth(depth, width, height);
}

// Marches one pixel's ray to its depth: the "raymarch" method, and the froxel method's
// fallback for the few pixels beyond its fitted depth range.
class PixelMarcher {
public:
    PixelMarcher(const AerialView& view, const AtmosphereLuts& luts, int width, int height)
        : view_(view),
          luts_(luts),
          rays_(view.camera, width, height),
          sun_(view.origin.sun_direction),
          colour_(view.atmosphere, view.exposure, view.color_space),
          steps_(view.options.raymarch_steps),
          top_(view.atmosphere.top_radius_m) {}

    struct Scratch {
        explicit Scratch(std::size_t C) : L(C), T(C) {}
        std::vector<float> L, T;
    };
    std::size_t channels() const { return colour_.channels(); }

    // Pixel (x, y) at Z-pass depth z >= 0 (not sky): RGB in-scattering and transmittance.
    void operator()(int x, int y, float z, Scratch& s, float* L3, float* T3) const {
        for (int c = 0; c < 3; ++c) {
            L3[c] = 0.0f;
            T3[c] = 1.0f;
        }
        if (!(z > 0.0f)) return;
        const CameraRays::Ray cam = rays_.at_pixel(x, y);
        const AirRay ray = air_ray(view_, cam, sun_);
        if (!march_ray(luts_, ray, top_, double(z) * cam.distance_per_depth, steps_, s.L.data(), s.T.data()))
            return;
        colour_.convert(s.L.data(), s.T.data(), L3, T3);
    }

private:
    const AerialView& view_;
    const AtmosphereLuts& luts_;
    CameraRays rays_;
    glm::dvec3 sun_;
    PassColour colour_;
    int steps_;
    double top_;
};

// The fraction of the finite depths the froxel volume's range covers; deeper pixels (a far
// ridge's last pixels, the Moon) are marched one by one instead of stretching every slice.
constexpr double kFittedFraction = 0.999;

// The depth below which kFittedFraction of the non-sky pixels lie (0 when all are sky).
double fitted_depth(std::span<const float> depth, double sky_depth_m) {
    std::vector<float> finite;
    finite.reserve(depth.size());
    for (const float z : depth)
        if (!is_sky_depth(z, sky_depth_m) && z > 0.0f) finite.push_back(z);
    if (finite.empty()) return 0.0;
    const std::size_t k = std::size_t(kFittedFraction * double(finite.size() - 1));
    std::nth_element(finite.begin(), finite.begin() + std::ptrdiff_t(k), finite.end());
    return double(finite[k]);
}

// The largest view-axis depth at which any froxel column's ray leaves the top of the
// atmosphere (0 when none is inside it): beyond it nothing changes along any column, so
// the fitted depth range never needs to reach further, however far the farthest surface
// is (a moon, the ground seen from orbit).
double atmosphere_exit_depth(const AerialView& view, int width, int height) {
    const CameraRays rays(view.camera, width, height);
    const int nx = view.options.froxel_width, ny = view.options.froxel_height;
    const double top = view.atmosphere.top_radius_m;
    double z = 0.0;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const CameraRays::Ray cam =
                rays.at_screen(double(i) / double(nx - 1), double(j) / double(ny - 1));
            const AirRay ray = air_ray(view, cam, glm::dvec3(0.0, 0.0, 1.0));
            double t0, t1;
            if (clip_to_atmosphere(ray, top, std::numeric_limits<double>::infinity(), t0, t1))
                z = std::max(z, t1 / cam.distance_per_depth);
        }
    return z;
}

AerialPasses allocate(int width, int height) {
    AerialPasses p;
    p.width = width;
    p.height = height;
    const std::size_t n = std::size_t(width) * std::size_t(height) * 3;
    p.inscatter.assign(n, 0.0f);
    p.transmittance.assign(n, 1.0f);
    return p;
}

}  // namespace

void validate_depth(std::span<const float> depth, int width, int height) {
    if (depth.size() != std::size_t(width) * std::size_t(height))
        throw InvalidArgument("depth", fmt::format("holds {} values, needs width x height = {} x {}",
                                                   depth.size(), width, height));
    for (std::size_t k = 0; k < depth.size(); ++k) {
        const float z = depth[k];
        if (z >= 0.0f) continue;  // +inf included
        const std::size_t x = k % std::size_t(width), y = k / std::size_t(width);
        throw InvalidArgument("depth", fmt::format("pixel (x {}, y {}, row 0 at the top) is {}; depths "
                                                   "must be >= 0 m (+inf or >= aerial.sky_depth_m marks "
                                                   "sky)",
                                                   x, y, std::isnan(z) ? "NaN" : fmt::format("{}", z)));
    }
}

double largest_finite_depth(std::span<const float> depth, double sky_depth_m) {
    double z_max = 0.0;
    for (const float z : depth)
        if (!is_sky_depth(z, sky_depth_m)) z_max = std::max(z_max, double(z));
    return z_max;
}

AerialPerspectiveVolume::AerialPerspectiveVolume(const AerialView& view, const AtmosphereLuts& luts,
                                                 int width, int height, double max_depth_m,
                                                 Progress* progress)
    : nx_(view.options.froxel_width),
      ny_(view.options.froxel_height),
      nz_(view.options.froxel_slices),
      max_depth_(max_depth_m) {
    view.validate();
    require_in_range("aerial.max_depth_m", max_depth_m, 1e-6, 1e12, "m");
    const CameraRays rays(view.camera, width, height);
    const glm::dvec3 sun = view.origin.sun_direction;
    const PassColour colour(view.atmosphere, view.exposure, view.color_space);
    inscatter_.assign(std::size_t(nx_) * ny_ * nz_ * 3, 0.0f);
    optical_depth_.assign(inscatter_.size(), 0.0f);
    march_grid(
        luts, colour, view.options.steps_per_slice, nx_, ny_, std::vector<double>(std::size_t(nz_)), progress,
        [&](int i, int j, std::vector<double>& distances) {
            const CameraRays::Ray cam =
                rays.at_screen(double(i) / double(nx_ - 1), double(j) / double(ny_ - 1));
            for (int k = 1; k <= nz_; ++k)
                distances[std::size_t(k - 1)] = slice_depth(k) * cam.distance_per_depth;
            return air_ray(view, cam, sun);
        },
        [&](int i, int j, const std::vector<float>& L, const std::vector<float>& T) {
            for (int k = 0; k < nz_; ++k) {
                const std::size_t at = index(i, j, k);
                for (int c = 0; c < 3; ++c) {
                    inscatter_[at + c] = L[std::size_t(k) * 3 + c];
                    optical_depth_[at + c] = optical_depth_of(T[std::size_t(k) * 3 + c]);
                }
            }
        });
}

double AerialPerspectiveVolume::slice_depth(int k) const {
    const double s = double(k) / double(nz_);
    return max_depth_ * s * s;
}

AerialPerspectiveVolume::Sample AerialPerspectiveVolume::sample(double sx, double sy, double depth) const {
    Sample out{{0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}};
    if (!(depth > 0.0)) return out;
    depth = std::min(depth, max_depth_);  // beyond the volume (or +inf): its last slice
    // Screen: bilinear between the four nearest columns.
    const double fx = clamp01(sx) * double(nx_ - 1), fy = clamp01(sy) * double(ny_ - 1);
    const int i = std::min(int(fx), nx_ - 2), j = std::min(int(fy), ny_ - 2);
    const float wx = float(fx - i), wy = float(fy - j);
    // Depth: the two slices around it (slice 0 is depth 0: L = 0, tau = 0), linear in depth.
    const double s = std::sqrt(depth / max_depth_) * double(nz_);
    const int k = std::min(int(s), nz_ - 1);  // depth lies between slices k and k + 1
    const double z0 = k == 0 ? 0.0 : slice_depth(k), z1 = slice_depth(k + 1);
    const float wz = float(clamp01((depth - z0) / (z1 - z0)));
    float L[3] = {0, 0, 0}, tau[3] = {0, 0, 0};
    const float wxy[4] = {(1 - wx) * (1 - wy), wx * (1 - wy), (1 - wx) * wy, wx * wy};
    const int di[4] = {0, 1, 0, 1}, dj[4] = {0, 0, 1, 1};
    for (int corner = 0; corner < 4; ++corner) {
        const std::size_t hi = index(i + di[corner], j + dj[corner], k);
        for (int c = 0; c < 3; ++c) {
            float l = wz * inscatter_[hi + c], t = wz * optical_depth_[hi + c];
            if (k > 0) {
                const std::size_t lo = index(i + di[corner], j + dj[corner], k - 1);
                l += (1 - wz) * inscatter_[lo + c];
                t += (1 - wz) * optical_depth_[lo + c];
            }
            L[c] += wxy[corner] * l;
            tau[c] += wxy[corner] * t;
        }
    }
    for (int c = 0; c < 3; ++c) {
        out.inscatter[c] = L[c];
        out.transmittance[c] = std::exp(-tau[c]);
    }
    return out;
}

// The frame-wide part, once (AerialFrame in the header): the checks, the LUTs, the fitted
// depth range and the froxel volume, or the LUTs and the marcher alone for "raymarch".
struct AerialFrame::Impl {
    Impl(const AerialView& s, std::span<const float> d, int w, int h, AerialOptions::Method m)
        : view(s), depth(d), width(w), height(h), method(m), sky(s.options.sky_depth_m) {
        check_call(view, depth, width, height);
        if (method == AerialOptions::Method::Froxel) {
            z_max = view.options.max_depth_m;
            fitted = !(z_max > 0.0);
            if (fitted) {
                z_max = fitted_depth(depth, sky);
                const double exit = atmosphere_exit_depth(view, width, height);
                if (exit > 0.0) z_max = std::min(z_max, exit);
            }
            if (!(z_max > 0.0)) return;  // nothing but sky (or depth 0): T = 1, L = 0 everywhere
        }
        luts = std::make_unique<AtmosphereLuts>(view.atmosphere, view.luts);
        // Build ~ a few percent of the work; the application is one lookup per pixel.
        if (method == AerialOptions::Method::Froxel)
            volume = std::make_unique<AerialPerspectiveVolume>(view, *luts, width, height, z_max, nullptr);
        march = std::make_unique<PixelMarcher>(view, *luts, width, height);
    }

    AerialView view;
    std::span<const float> depth;
    int width, height;
    AerialOptions::Method method;
    double sky, z_max = 0.0;
    bool fitted = false;
    std::unique_ptr<AtmosphereLuts> luts;
    std::unique_ptr<AerialPerspectiveVolume> volume;
    std::unique_ptr<PixelMarcher> march;
};

AerialFrame::AerialFrame(const AerialView& view, std::span<const float> depth, int width, int height,
                         std::optional<AerialOptions::Method> method)
    : impl_(std::make_unique<Impl>(view, depth, width, height, method.value_or(view.options.method))) {}

AerialFrame::~AerialFrame() = default;

void AerialFrame::render(RowRange rows_in, std::span<float> inscatter, std::span<float> transmittance,
                         Progress* progress) const {
    const Impl& f = *impl_;
    const RowRange band = rows_in.resolved(f.height);
    const std::size_t w = std::size_t(f.width), n = std::size_t(band.size()) * w * 3;
    if (inscatter.size() != n || transmittance.size() != n)
        throw InvalidArgument("rows", fmt::format("passes of {} values for a band of {} rows of {} pixels",
                                                  inscatter.size(), band.size(), f.width));
    std::fill(inscatter.begin(), inscatter.end(), 0.0f);
    std::fill(transmittance.begin(), transmittance.end(), 1.0f);
    if (!f.march) {  // nothing but sky
        if (progress && !progress->report(1.0)) throw Cancelled();
        return;
    }
    ProgressTracker tracker(progress, std::size_t(band.size()));
    tbb::parallel_for(
        tbb::blocked_range<int>(band.begin, band.end), [&](const tbb::blocked_range<int>& rows) {
            PixelMarcher::Scratch scratch(f.march->channels());
            for (int y = rows.begin(); y != rows.end(); ++y) {
                const double sy = (double(y) + 0.5) / double(f.height);
                for (int x = 0; x < f.width; ++x) {
                    const std::size_t p = std::size_t(y) * w + std::size_t(x);
                    const std::size_t o = (std::size_t(y - band.begin) * w + std::size_t(x)) * 3;
                    const float z = f.depth[p];
                    if (is_sky_depth(z, f.sky)) continue;
                    // "raymarch", and the froxel way's pixels beyond its fitted range.
                    if (!f.volume || (f.fitted && double(z) > f.z_max)) {
                        (*f.march)(x, y, z, scratch, &inscatter[o], &transmittance[o]);
                        continue;
                    }
                    const AerialPerspectiveVolume::Sample s =
                        f.volume->sample((double(x) + 0.5) / double(f.width), sy, double(z));
                    for (int c = 0; c < 3; ++c) {
                        inscatter[o + c] = s.inscatter[c];
                        transmittance[o + c] = s.transmittance[c];
                    }
                }
                tracker.advance();
            }
        });
    tracker.finish();
}

namespace {

// The whole frame's passes with only `rows` computed, by either way.
AerialPasses whole_frame(const AerialView& view, std::span<const float> depth, int width, int height,
                         Progress* progress, RowRange rows_in, AerialOptions::Method method) {
    const AerialFrame frame(view, depth, width, height, method);
    const RowRange band = rows_in.resolved(height);
    AerialPasses passes = allocate(width, height);
    const std::size_t q0 = std::size_t(band.begin) * std::size_t(width) * 3;
    const std::size_t n = std::size_t(band.size()) * std::size_t(width) * 3;
    frame.render(band, std::span<float>(passes.inscatter).subspan(q0, n),
                 std::span<float>(passes.transmittance).subspan(q0, n), progress);
    return passes;
}

}  // namespace

AerialPasses aerial_perspective_froxel(const AerialView& view, std::span<const float> depth, int width,
                                       int height, Progress* progress, RowRange rows) {
    return whole_frame(view, depth, width, height, progress, rows, AerialOptions::Method::Froxel);
}

AerialPasses aerial_perspective_raymarch(const AerialView& view, std::span<const float> depth, int width,
                                         int height, Progress* progress, RowRange rows) {
    return whole_frame(view, depth, width, height, progress, rows, AerialOptions::Method::Raymarch);
}

AerialPasses aerial_perspective(const AerialView& view, std::span<const float> depth, int width, int height,
                                Progress* progress, RowRange rows) {
    return whole_frame(view, depth, width, height, progress, rows, view.options.method);
}

AirAlongRays aerial_along_rays(const Atmosphere& atmosphere, const AtmosphereLuts& luts,
                               const glm::dvec3& planet_centre, const glm::dvec3& sun_direction,
                               std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                               std::span<const double> distances, int steps, double exposure, bool spectral,
                               ColorSpace color_space) {
    const std::size_t n = directions.size();
    if (distances.size() != n)
        throw InvalidArgument("distances",
                              fmt::format("has {} values for {} directions", distances.size(), n));
    if (origins.size() != 1 && origins.size() != n)
        throw InvalidArgument(
            "origins", fmt::format("has {} points for {} directions (1 or one per ray)", origins.size(), n));
    require_in_range("steps", steps, 1, 1 << 20, "steps");
    const PassColour colour(atmosphere, exposure, color_space);
    const std::size_t C = colour.channels();
    const glm::dvec3 sun = glm::normalize(sun_direction);
    const double top = atmosphere.top_radius_m;
    AirAlongRays out;
    out.inscatter.assign(n * 3, 0.0f);
    out.transmittance.assign(n * 3, 1.0f);
    if (spectral) {
        out.inscatter_spectral.assign(n * C, 0.0f);
        out.transmittance_spectral.assign(n * C, 1.0f);
    }
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
            std::vector<float> L(C), T(C);
            for (std::size_t q = r.begin(); q != r.end(); ++q) {
                if (!(distances[q] > 0.0)) continue;
                const AirRay ray{origins[origins.size() == 1 ? 0 : q] - planet_centre, directions[q], sun};
                std::fill(L.begin(), L.end(), 0.0f);
                std::fill(T.begin(), T.end(), 1.0f);
                if (!march_ray(luts, ray, top, distances[q], steps, L.data(), T.data())) continue;
                colour.convert(L.data(), T.data(), &out.inscatter[q * 3], &out.transmittance[q * 3]);
                if (spectral) {
                    std::copy(L.begin(), L.end(), out.inscatter_spectral.begin() + std::ptrdiff_t(q * C));
                    std::copy(T.begin(), T.end(), out.transmittance_spectral.begin() + std::ptrdiff_t(q * C));
                }
            }
        });
    return out;
}

const char* aerial_method_name(AerialOptions::Method method) {
    return method == AerialOptions::Method::Froxel ? "froxel" : "raymarch";
}

AerialOptions::Method aerial_method_from_name(const std::string& name, const std::string& parameter) {
    if (name == "froxel") return AerialOptions::Method::Froxel;
    if (name == "raymarch") return AerialOptions::Method::Raymarch;
    throw InvalidArgument(parameter, fmt::format("must be \"froxel\" (Hillaire 2020's camera volume) or "
                                                 "\"raymarch\" (every pixel marched), got \"{}\"",
                                                 name));
}

void AerialOptions::validate(const std::string& p) const {
    require_in_range(p + ".froxels[0]", froxel_width, 2, 1024, "columns");
    require_in_range(p + ".froxels[1]", froxel_height, 2, 1024, "rows");
    require_in_range(p + ".froxels[2]", froxel_slices, 1, 1024, "slices");
    if (double(froxel_width) * froxel_height * froxel_slices > double(1 << 26))
        throw InvalidArgument(p + ".froxels", "more than 2^26 froxels");
    require_in_range(p + ".max_depth_m", max_depth_m, 0.0, 1e12, "m (0: fitted to the depth)");
    require_in_range(p + "steps_per_slice", steps_per_slice, 1, 256);
    require_in_range(p + ".raymarch_steps", raymarch_steps, 1, 4096);
    require_in_range(p + ".sky_depth_m", sky_depth_m, 1.0, 1e30, "m");
}

void AerialView::validate() const {
    atmosphere.validate();
    luts.validate();
    origin.validated();
    camera.validate();
    require_in_range("width", width, 1, std::numeric_limits<int>::max(), "pixels");
    require_in_range("height", height, 1, std::numeric_limits<int>::max(), "pixels");
    require_in_range("exposure", exposure, 1e-12, 1e6);  // as SceneDescription's
    options.validate();
}

}  // namespace welkin
