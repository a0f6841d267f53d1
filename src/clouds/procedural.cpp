// SPDX-License-Identifier: Apache-2.0
// A procedural cloud layer; see procedural.hpp.
#include "welkin/clouds/procedural.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {
namespace {

double clamp01d(double x) { return std::clamp(x, 0.0, 1.0); }

// Schneider's remap: x from [lo, hi] to [new_lo, new_hi], linear, not clamped.
double remap(double x, double lo, double hi, double new_lo, double new_hi) {
    const double span = hi - lo;
    if (!(std::abs(span) > 1e-12)) return x >= hi ? new_hi : new_lo;
    return new_lo + (x - lo) / span * (new_hi - new_lo);
}

// The noise of one seed is baked once per process and shared by every layer using it
// (a few seconds of CPU for the 64^3 base texture; 5 MiB). The last kCachedSeeds seeds
// stay baked (an animation or a UI changing other parameters reuses them).
constexpr std::size_t kCachedSeeds = 4;
std::shared_ptr<const CloudNoiseTextures> shared_noise(std::uint64_t seed) {
    static std::mutex mutex;
    static std::vector<std::pair<std::uint64_t, std::shared_ptr<const CloudNoiseTextures>>> cache;
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& [s, p] : cache)
        if (s == seed) return p;
    auto p = std::make_shared<const CloudNoiseTextures>(CloudNoiseTextures::bake(seed));
    if (cache.size() >= kCachedSeeds) cache.erase(cache.begin());
    cache.emplace_back(seed, p);
    return p;
}

// The ray's distance l from the centre and b = d . (o - c), shared by concentric spheres.
struct CentreOffset {
    double l, b;
    CentreOffset(const CloudRay& ray, const glm::dvec3& c) {
        const glm::dvec3 oc = ray.origin - c;
        l = glm::length(oc);
        b = glm::dot(ray.direction, oc);
    }
};

// The segment [t0, t1] of the ray (o: its offset from the centre c) inside the sphere of radius r about c:
// roots of t^2 + 2 b t + q = 0, b = d . (o - c), q = |o - c|^2 - r^2 = (|o - c| - r)(|o - c| + r) (factored
// so that a point near the sphere keeps its digits). False if it misses.
bool sphere_interval(const CentreOffset& o, double r, double& t0, double& t1) {
    const double q = (o.l - r) * (o.l + r);
    const double disc = o.b * o.b - q;
    if (disc < 0.0) return false;
    const double s = std::sqrt(disc);
    // Numerically stable pair: the root of larger magnitude first, the other from q.
    const double big = o.b > 0.0 ? -o.b - s : -o.b + s;
    const double other = big != 0.0 ? q / big : 0.0;
    t0 = std::min(big, other);
    t1 = std::max(big, other);
    return true;
}

// The shape of each type (header): its height gradient's corners, how much of the layer
// the towers leave out where the weather map's g is low, the height fraction below which
// erosion fades (a flat base), the stretch of the noise along its streak direction, and
// the curl distortion of the erosion (in detail tiles).
struct Trapezoid {
    double a0, a1, a2, a3;
    double operator()(double x) const {
        return clamp01d(remap(x, a0, a1, 0.0, 1.0)) * clamp01d(remap(x, a2, a3, 1.0, 0.0));
    }
};
struct TypeShape {
    Trapezoid gradient;
    double towers, base_erosion, stretch, curl;
    double fibres;  // how much the detail noise shapes the whole cloud, not only its edges
    // cells (cumulus, stratocumulus, altocumulus): 1 builds the cloud from its footprint
    // (flat base, a heap narrowing upwards, lobes); 0 the layer model (stratus). billow: the
    // lobes' depth over their cells' size (1: balls of half a cell's radius); dome: the
    // small cells' height over their width (a larger one, taller heaps).
    double cells, billow, dome;
    // cirrus: the fallstreaks' length below the heads (a fraction of the layer, times the
    // footprint's strength), their drift along the streaks at the bottom (shear) and across
    // them (hook, growing as the square of the depth: the hook), in base tiles.
    double fall, shear, hook;
};
const TypeShape& shape_of(CloudType t) {
    // cumulus: a flat base (steep rise, no lobes at the bottom), towers where the weather
    //   map says so, heaps narrowing upwards with cauliflower tops of lobes on lobes;
    // stratocumulus: a lumpy layer of low, broad heaps, somewhat stretched;
    // altocumulus: a thin mid-level sheet of small rounded cells;
    // stratus: a low, uniform grey sheet with faint, stretched undulations;
    // cirrus: thin high heads of tufts with sheared, hooked fallstreaks of fibres below.
    static const TypeShape shapes[] = {
        {{0.0, 0.04, 0.45, 1.0}, 0.65, 0.06, 1.0, 0.3, 0.0, 1.0, 0.8, 1.2, 0.0, 0.0, 0.0},  // cumulus
        {{0.0, 0.06, 0.5, 0.95}, 0.35, 0.08, 1.6, 0.3, 0.0, 1.0, 0.4, 0.8, 0.0, 0.0, 0.0},  // stratocumulus
        {{0.0, 0.08, 0.55, 0.95}, 0.3, 0.08, 1.0, 0.4, 0.0, 1.0, 0.4, 1.0, 0.0, 0.0, 0.0},  // altocumulus
        {{0.0, 0.1, 0.75, 1.0}, 0.0, 0.0, 1.5, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},     // stratus
        {{0.78, 0.85, 0.94, 1.0}, 0.3, 0.0, 4.0, 0.8, 2.0, 0.0, 0.0, 0.0, 1.0, 1.5, 2.4},   // cirrus
    };
    return shapes[static_cast<int>(t)];
}

// The streaks' direction: 30 degrees off the x axis (cos, sin), so that no structure runs
// along the world's axes.
constexpr double kStreakCos = 0.8660254037844386, kStreakSin = 0.5;
// How far (a height fraction) the clear-air tests stay from the shape's bounds: far above
// the formulas' rounding (1e-16), far below any structure (1e-9 of a layer is a micrometre).
constexpr double kBandMargin = 1e-9;
// How far in from a cell's footprint edge m reaches 1, in base tiles (about a Worley cell's
// radius: cell_density).
constexpr double kFootprintReach = 0.12;
// The heap's profile over its footprint, f_top = H u^kDomeExponent with u = 1 - r^2 / rho^2
// (cell_density): 1 is a paraboloid of revolution, 1/2 the cap of an ellipsoid (vertical
// at the foot, the flattest top). 0.6 rounds the tops and still narrows upwards as
// tests/python/test_cloud_looks.py asks (the area above a quarter and half of the height).
constexpr double kDomeExponent = 0.6;
// Internal coverage at which a layer is overcast (clamp(k (1 - weather_variation)) = 1
// for weather_variation <= 0.75).
constexpr double kMaxInternalCoverage = 4.0;

// The calibration's cache: the internal coverage of every layer built so far, keyed by
// everything that shapes the field but the wind (a shift does not change the share; the
// evolution, which changes the shapes, is in the key).
std::mutex calibration_mutex;
std::map<std::tuple<int, double, double, double, double, double, double, double, double, double,
                    std::uint64_t, double, double, double>,
         double>
    calibration_cache;

// The base shape of the header, base = remap(pw, -(1 - fbm_w), 1, 0, 1), from a blended
// read b = (pw, fbm_w) of the base texture.
double base_shape(const float* b) { return clamp01d(remap(b[0], -(1.0 - b[1]), 1.0, 0.0, 1.0)); }

// The salts of the hex taps (hex_read) of the weather map and of the base texture (base_at
// and slice_at read the same taps).
constexpr std::uint64_t kWeatherTaps = 0x57ea7e5, kBaseTaps = 0xba5e;

// A hex-tiled read (noise.hpp, hex_taps), the lattice half a texture period apart: every
// channel is its mean over the texture plus the weighted deviations of the taps, each tap
// the texture read at height z, times the taps' contrast factor, clamped to the channel's
// range [0, 1]. With one tap (weight 1, contrast 1) that is the tap's read itself, to the
// double rounding that the conversion to float drops. The offsets move in the plane only:
// the base shape still repeats through the height (evolution_m cycles).
template <int N>
void hex_read(const PeriodicTexture<N>& texture, const double* mean, double u, double v, double z,
              std::uint64_t seed, float* out) {
    HexTaps taps;
    hex_taps(u, v, 0.5, seed, taps);
    if (taps.count == 1) {  // half the plane
        texture.sample(u + taps.du[0], v + taps.dv[0], z, out);
        for (int c = 0; c < N; ++c) out[c] = std::clamp(out[c], 0.0f, 1.0f);
        return;
    }
    double acc[N] = {};
    for (int t = 0; t < taps.count; ++t) {
        float r[N];
        texture.sample(u + taps.du[t], v + taps.dv[t], z, r);
        for (int c = 0; c < N; ++c) acc[c] += taps.weight[t] * (r[c] - mean[c]);
    }
    for (int c = 0; c < N; ++c) out[c] = float(clamp01d(mean[c] + taps.contrast * acc[c]));
}

// The footprints' slice (header; footprint()): the base texture's n x n texels at the
// height z, its two channels as they are (a bilinear read of it is the base texture's
// trilinear read at z), and for cells a third channel, the peak map. The peak map: the
// footprint's base slice S (remapped as footprint() does) split into basins, each texel's
// basin found by steepest ascent over its 8 neighbours on S smoothed by a Gaussian of two
// texels (so that the fine Worley octaves' bumps, which are the lobes' scale, do not each
// make a cell of their own), and each texel holding its basin's highest S. So peak >= S at
// every texel; across a basin's boundary the map steps, and the bilinear lookup ramps it
// over a texel. peak_mean: the peak map's mean (0 without it).
PeriodicTexture<3> bake_slice(const PeriodicTexture<2>& base, int n, double z, bool peaks,
                              double& peak_mean) {
    PeriodicTexture<3> slice(n, n, 1);
    std::vector<double> S(std::size_t(n) * n), G(std::size_t(n) * n);
    const auto at = [n](int i, int j) { return std::size_t((j + n) % n) * n + std::size_t((i + n) % n); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            float* b = slice.at(i, j, 0);
            base.sample((i + 0.5) / n, (j + 0.5) / n, z, b);
            b[2] = 0.0f;
            S[at(i, j)] = base_shape(b);
        }
    peak_mean = 0.0;
    if (!peaks) return slice;
    // Separable Gaussian, sigma 2 texels, periodic.
    constexpr int kR = 6;
    double w[2 * kR + 1], wsum = 0.0;
    for (int k = -kR; k <= kR; ++k) wsum += w[k + kR] = std::exp(-0.5 * (k * k) / 4.0);
    const auto blur = [&](const std::vector<double>& src, std::vector<double>& dst, int di, int dj) {
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                double a = 0.0;
                for (int k = -kR; k <= kR; ++k) a += w[k + kR] * src[at(i + k * di, j + k * dj)];
                dst[at(i, j)] = a / wsum;
            }
    };
    std::vector<double> tmp(S.size());
    blur(S, tmp, 1, 0);
    blur(tmp, G, 0, 1);
    // Steepest ascent on G: each texel's uphill neighbour (itself at a maximum), followed to
    // its root; the highest S of each root's basin.
    std::vector<std::size_t> up(S.size());
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            std::size_t best = at(i, j);
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di)
                    if (G[at(i + di, j + dj)] > G[best]) best = at(i + di, j + dj);
            up[at(i, j)] = best;
        }
    std::vector<std::size_t> root(S.size());
    std::vector<double> top(S.size(), 0.0);
    for (std::size_t p = 0; p < S.size(); ++p) {
        std::size_t q = p;
        while (up[q] != q) q = up[q];  // G strictly rises along the path: it ends
        root[p] = q;
        top[q] = std::max(top[q], S[p]);
    }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double v = top[root[at(i, j)]];
            slice.at(i, j, 0)[2] = float(v);
            peak_mean += v / (double(n) * n);
        }
    return slice;
}

}  // namespace

std::string_view cloud_type_name(CloudType type) { return kCloudTypeNames[static_cast<int>(type)]; }

std::string_view coverage_measure_name(CloudCoverageMeasure measure) {
    return kCoverageMeasureNames[static_cast<int>(measure)];
}

CloudCoverageMeasure coverage_measure_from_name(std::string_view name, const std::string& parameter) {
    for (std::size_t i = 0; i < kCoverageMeasureNames.size(); ++i)
        if (kCoverageMeasureNames[i] == name) return static_cast<CloudCoverageMeasure>(i);
    throw InvalidArgument(parameter, fmt::format("must be \"area\" or \"dome\", got \"{}\"", name));
}

CloudType cloud_type_from_name(std::string_view name, const std::string& parameter) {
    for (std::size_t i = 0; i < kCloudTypeNames.size(); ++i)
        if (kCloudTypeNames[i] == name) return static_cast<CloudType>(i);
    std::string list;
    for (const auto n : kCloudTypeNames) list += fmt::format("{}\"{}\"", list.empty() ? "" : ", ", n);
    throw InvalidArgument(parameter, fmt::format("must be one of {}, got \"{}\"", list, name));
}

// Altitudes, thicknesses and scales typical of each genus (WMO International Cloud Atlas:
// cumulus bases 0.5-2 km with towers to a few km; stratocumulus a low layer of rolls a few
// hundred metres thick; altocumulus 2-6 km, cells 0.2-1 km; stratus below 1 km, a sheet
// that hides the sun; cirrus 6-12 km, thin ice streaks of optical depth ~ 0.1-1).
CloudLayerParams CloudLayerParams::preset(CloudType type) {
    CloudLayerParams p;
    p.cloud_type = type;
    switch (type) {
        case CloudType::cumulus:
            p.base_scale_m = 8000.0;  // cells 1-2 km across
            break;
        case CloudType::stratocumulus:
            p.bottom_altitude_m = 1000.0, p.top_altitude_m = 1800.0, p.coverage = 0.7, p.density_per_m = 0.03;
            p.base_scale_m = 2500.0, p.detail_scale_m = 500.0, p.weather_scale_m = 25000.0;
            p.detail_strength = 0.45, p.weather_variation = 0.4;
            break;
        case CloudType::altocumulus:
            p.bottom_altitude_m = 4000.0, p.top_altitude_m = 4500.0, p.coverage = 0.5, p.density_per_m = 0.02;
            p.base_scale_m = 1500.0, p.detail_scale_m = 300.0, p.weather_scale_m = 10000.0;
            p.detail_strength = 0.5, p.weather_variation = 0.5;
            break;
        case CloudType::stratus:
            p.bottom_altitude_m = 400.0, p.top_altitude_m = 900.0, p.coverage = 1.0, p.density_per_m = 0.04;
            p.base_scale_m = 8000.0, p.detail_scale_m = 900.0, p.weather_scale_m = 60000.0;
            p.detail_strength = 0.35, p.weather_variation = 0.3;
            break;
        case CloudType::cirrus:
            p.bottom_altitude_m = 8000.0, p.top_altitude_m = 9500.0, p.coverage = 0.3,
            p.density_per_m = 0.008;
            p.base_scale_m = 3000.0, p.detail_scale_m = 800.0, p.weather_scale_m = 60000.0;
            p.detail_strength = 0.6, p.weather_variation = 0.6;
            break;
    }
    return p;
}

void CloudLayerParams::validate() const {
    if (static_cast<int>(cloud_type) < 0 || static_cast<int>(cloud_type) >= int(kCloudTypeNames.size()))
        throw InvalidArgument("cloud_type", "must be one of the CloudType values");
    if (coverage_measure != CloudCoverageMeasure::area && coverage_measure != CloudCoverageMeasure::dome)
        throw InvalidArgument("coverage_measure", "must be area or dome");
    require_in_range("bottom_altitude_m", bottom_altitude_m, 0.0, 20000.0, "m");
    require_in_range("top_altitude_m", top_altitude_m, 0.0, 20000.0, "m");
    if (!(top_altitude_m > bottom_altitude_m))
        throw InvalidArgument("top_altitude_m",
                              fmt::format("must be above bottom_altitude_m ({} m), got {} m",
                                          bottom_altitude_m, top_altitude_m));
    require_in_range("coverage", coverage, 0.0, 1.0);
    require_in_range("density_per_m", density_per_m, 0.0, 10.0, "m^-1");
    require_in_range("base_scale_m", base_scale_m, 10.0, 1e6, "m");
    require_in_range("detail_scale_m", detail_scale_m, 1.0, 1e6, "m");
    require_in_range("weather_scale_m", weather_scale_m, 10.0, 1e7, "m");
    require_in_range("detail_strength", detail_strength, 0.0, 1.0);
    require_in_range("weather_variation", weather_variation, 0.0, 1.0);
    // Beyond 1e9 m the field's coordinates (x - wind) lose the noise's resolution in a
    // double (1e20 m: every point reads one texel), and the layer vanishes.
    require_in_range("wind_offset_m[0]", wind_offset_m.x, -1e9, 1e9, "m");
    require_in_range("wind_offset_m[1]", wind_offset_m.y, -1e9, 1e9, "m");
    if (!(std::abs(evolution_m) <= 1e9))
        throw InvalidArgument("evolution_m",
                              fmt::format("must be finite, in [-1e9, 1e9] m, got {}", evolution_m));
    require_in_range("planet_radius_m", planet_radius_m, 1e3, 1e8, "m");
    require_in_range("origin_altitude_m", origin_altitude_m, 0.0, 1e6, "m");
}

ProceduralClouds::ProceduralClouds(const CloudLayerParams& params) : p_(params) {
    p_.validate();
    centre_ = {0.0, 0.0, -(p_.planet_radius_m + p_.origin_altitude_m)};
    noise_ = shared_noise(p_.seed);
    // The fixed linear combinations of the noise channels (see the header's formulas).
    const auto& nb = noise_->base;
    const int n = nb.size();
    base_ = PeriodicTexture<2>(n, n, n);
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const glm::vec4 v = nb.at(i, j, k);
                base_.at(i, j, k)[0] = v.r;
                base_.at(i, j, k)[1] = 0.625f * v.g + 0.25f * v.b + 0.125f * v.a;
            }
    const auto& nd = noise_->detail;
    const int m = nd.size();
    detail_ = PeriodicTexture<4>(m, m, m);
    for (int k = 0; k < m; ++k)
        for (int j = 0; j < m; ++j)
            for (int i = 0; i < m; ++i) {
                const glm::vec4 v = nd.at(i, j, k);
                float* t = detail_.at(i, j, k);
                t[0] = 0.625f * v.r + 0.25f * v.g + 0.125f * v.b;
                t[1] = v.r, t[2] = v.g, t[3] = v.b;
            }
    const auto& nw = noise_->weather;
    const int q = nw.size();
    weather_ = PeriodicTexture<4>(q, q, 1);
    for (int j = 0; j < q; ++j)
        for (int i = 0; i < q; ++i)
            for (int c = 0; c < 4; ++c) weather_.at(i, j, 0)[c] = nw.at(i, j, 0)[c];
    const auto& nc = noise_->curl;
    const int qc = nc.size();
    curl_ = PeriodicTexture<2>(qc, qc, 1);
    for (int j = 0; j < qc; ++j)
        for (int i = 0; i < qc; ++i)
            for (int c = 0; c < 2; ++c) curl_.at(i, j, 0)[c] = nc.at(i, j, 0)[c];
    for (int j = 0; j < q; ++j)
        for (int i = 0; i < q; ++i)
            for (int c = 0; c < 4; ++c) weather_mean_[c] += weather_.at(i, j, 0)[c] / (double(q) * q);
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                for (int c = 0; c < 2; ++c) base_mean_[c] += base_.at(i, j, k)[c] / (double(n) * n * n);
    inv_weather_ = 1.0 / p_.weather_scale_m;
    inv_base_ = 1.0 / p_.base_scale_m;
    inv_detail_ = 1.0 / p_.detail_scale_m;
    thickness_ = p_.top_altitude_m - p_.bottom_altitude_m;
    inv_thickness_ = 1.0 / thickness_;
    sqrt_stretch_ = std::sqrt(shape_of(p_.cloud_type).stretch);
    slice_ =
        bake_slice(base_, n, p_.evolution_m * inv_base_, shape_of(p_.cloud_type).cells > 0.0, peak_mean_);

    // The band of heights the type's shape can fill (the header): a cell's ceiling at the
    // highest local top (cell_ceiling rises with f_max, which is 1 where the towers are
    // full); the longest fallstreak's foot (m <= 1); the layer model's trapezoid under the
    // lowest and highest local tops. Widened by kBandMargin, far above the rounding of
    // the formulas, so that a skipped point is clear air.
    const TypeShape& shape = shape_of(p_.cloud_type);
    if (shape.fall > 0.0) {
        band_lo_ = std::min(shape.gradient.a0, shape.gradient.a1 * (1.0 - shape.fall));
    } else if (shape.cells > 0.0) {
        band_hi_ = cell_ceiling(1.0);
    } else {
        band_lo_ = shape.gradient.a0 * (1.0 - shape.towers);
        band_hi_ = shape.gradient.a3;
    }
    band_lo_ = std::max(0.0, band_lo_ - kBandMargin);
    band_hi_ = std::min(1.0, band_hi_ + kBandMargin);

    // The internal coverage k whose share of cloudy columns is `coverage` (header).
    if (p_.coverage <= 0.0 || p_.density_per_m <= 0.0) {
        k_ = 0.0;
        return;
    }
    if (p_.coverage >= 1.0) {
        k_ = kMaxInternalCoverage;
        return;
    }
    const auto key = std::make_tuple(
        static_cast<int>(p_.cloud_type) * 2 + static_cast<int>(p_.coverage_measure), p_.bottom_altitude_m,
        p_.top_altitude_m, p_.coverage, p_.density_per_m, p_.base_scale_m, p_.detail_scale_m,
        p_.weather_scale_m, p_.detail_strength, p_.weather_variation, p_.seed, p_.planet_radius_m,
        p_.origin_altitude_m, p_.evolution_m);
    {
        std::lock_guard<std::mutex> lock(calibration_mutex);
        if (const auto it = calibration_cache.find(key); it != calibration_cache.end()) {
            k_ = it->second;
            return;
        }
    }
    double lo = 0.0, hi = kMaxInternalCoverage;
    for (int it = 0; it < 14; ++it) {  // k to 4 / 2^14
        const double mid = 0.5 * (lo + hi);
        const double share = p_.coverage_measure == CloudCoverageMeasure::dome
                                 ? dome_share(mid, kDomeObservers, kDomeDirections)
                                 : fraction(mid, kCoverageColumns);
        (share < p_.coverage ? lo : hi) = mid;
    }
    k_ = 0.5 * (lo + hi);
    std::lock_guard<std::mutex> lock(calibration_mutex);
    if (calibration_cache.size() > 256) calibration_cache.clear();
    calibration_cache[key] = k_;
}

double ProceduralClouds::height_gradient(CloudType type, double f) {
    if (!(f >= 0.0 && f <= 1.0)) return 0.0;
    return shape_of(type).gradient(f);
}

// Vertical optical depth of the column above the world point (x, y) (density applies the wind) through
// the layer, midpoint rule in 32 steps, stopped once it reaches the coverage threshold.
double ProceduralClouds::column_depth(double x, double y, double k) const {
    constexpr int kSteps = 32;
    const double dh = (p_.top_altitude_m - p_.bottom_altitude_m) / kSteps;
    double tau = 0.0;
    for (int i = 0; i < kSteps && tau < kCoverageOpticalDepth; ++i) {
        const double h = p_.bottom_altitude_m + (i + 0.5) * dh;
        tau += p_.density_per_m * density({x, y, 0.0}, h, k) * dh;
    }
    return tau;
}

double ProceduralClouds::fraction(double k, int columns) const {
    // R2 low-discrepancy points (Roberts 2018, the plastic number's powers) over a square of
    // two weather tiles, in the field's own frame: the wind translates the field, so the
    // points move with it and the share (hence k, and the calibration's cache) is the same
    // for every wind offset.
    constexpr double a1 = 0.7548776662466927, a2 = 0.5698402909980532;
    const double side = 2.0 * p_.weather_scale_m;
    const int cloudy = tbb::parallel_reduce(
        tbb::blocked_range<int>(0, columns, 64), 0,
        [&](const tbb::blocked_range<int>& r, int acc) {
            for (int i = r.begin(); i != r.end(); ++i) {
                const double u = std::fmod(0.5 + a1 * (i + 1), 1.0), v = std::fmod(0.5 + a2 * (i + 1), 1.0);
                acc += column_depth(side * u + p_.wind_offset_m.x, side * v + p_.wind_offset_m.y, k) >=
                       kCoverageOpticalDepth;
            }
            return acc;
        },
        [](int a, int b) { return a + b; });
    return double(cloudy) / columns;
}

double ProceduralClouds::covered_fraction(int columns) const {
    if (columns < 1) throw InvalidArgument("columns", fmt::format("must be >= 1, got {}", columns));
    return fraction(k_, columns);
}

double ProceduralClouds::dome_fraction(int observers, int directions) const {
    require_in_range("observers", observers, 1, 4096);
    require_in_range("directions", directions, 1, 65536);
    return dome_share(k_, observers, directions);
}

// The slant optical depth along the ray through the shell, by the midpoint rule in 64 steps
// spread over its segments (as march_optical_depth, clouds/depth_grid.hpp), stopped once it
// reaches the coverage threshold.
double ProceduralClouds::slant_depth(const CloudRay& ray, double k,
                                     std::vector<MajorantSegment>& segs) const {
    constexpr int kSteps = 64;
    shell(ray, 1e6, segs);
    double total = 0.0;
    for (const auto& s : segs) total += s.t1 - s.t0;
    if (!(total > 0.0)) return 0.0;
    double tau = 0.0;
    for (const auto& s : segs) {
        const int n = std::max(1, int(std::ceil((s.t1 - s.t0) / (total / kSteps) - 1e-9)));
        const double dt = (s.t1 - s.t0) / n;
        for (int i = 0; i < n && tau < kCoverageOpticalDepth; ++i) {
            const glm::dvec3 x = ray.at(s.t0 + (i + 0.5) * dt);
            tau += p_.density_per_m * density(x, glm::length(x - centre_) - p_.planet_radius_m, k) * dt;
        }
    }
    return tau;
}

// The dome share (header) at internal coverage k: observers on the ground below R2 points
// of the columns' square (field frame, so the wind moves them with the field), directions
// of equal solid angle above kDomeMinElevationDeg (sin(elevation) uniform, R2 points in
// (sin(elevation), azimuth)).
double ProceduralClouds::dome_share(double k, int observers, int directions) const {
    constexpr double a1 = 0.7548776662466927, a2 = 0.5698402909980532;
    const double side = 2.0 * p_.weather_scale_m;
    const double s0 = std::sin(kDomeMinElevationDeg * kPi / 180.0);
    const int rays = observers * directions;
    const int covered = tbb::parallel_reduce(
        tbb::blocked_range<int>(0, rays, 16), 0,
        [&](const tbb::blocked_range<int>& r, int acc) {
            std::vector<MajorantSegment> segs;
            for (int i = r.begin(); i != r.end(); ++i) {
                const int o = i / directions, d = i % directions;
                // The observer: on the ground below the point (x, y) of the world.
                const double x = side * std::fmod(0.5 + a1 * (o + 1), 1.0) + p_.wind_offset_m.x;
                const double y = side * std::fmod(0.5 + a2 * (o + 1), 1.0) + p_.wind_offset_m.y;
                const glm::dvec3 up = glm::normalize(glm::dvec3(x, y, 0.0) - centre_);
                // (a metre up: a point on the ground sphere may round into it, and its rays stop there)
                const glm::dvec3 ground = centre_ + (p_.planet_radius_m + 1.0) * up;
                const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0.0, 1.0, 0.0), up));
                const glm::dvec3 north = glm::cross(up, east);
                const double sin_el = s0 + (1.0 - s0) * std::fmod(0.5 + a1 * (d + 1), 1.0);
                const double cos_el = std::sqrt(std::max(0.0, 1.0 - sin_el * sin_el));
                const double az = kTwoPi * std::fmod(0.5 + a2 * (d + 1), 1.0);
                const glm::dvec3 dir = sin_el * up + cos_el * (std::cos(az) * east + std::sin(az) * north);
                acc += slant_depth({ground, dir}, k, segs) >= kCoverageOpticalDepth;
            }
            return acc;
        },
        [](int a, int b) { return a + b; });
    return double(covered) / rays;
}

double ProceduralClouds::sigma_t(const glm::dvec3& p) const {
    if (!(k_ > 0.0) || !(p_.density_per_m > 0.0)) return 0.0;
    const double h = glm::length(p - centre_) - p_.planet_radius_m;
    return p_.density_per_m * density(p, h, k_);
}

// The normalised density (header) at p, altitude h, internal coverage k.
double ProceduralClouds::density(const glm::dvec3& p, double h, double k, bool skip) const {
    const double f = (h - p_.bottom_altitude_m) * inv_thickness_;
    if (!(f > 0.0 && f < 1.0)) return 0.0;
    if (skip && !(f > band_lo_ && f < band_hi_)) return 0.0;  // clear air by construction
    const TypeShape& shape = shape_of(p_.cloud_type);
    const double x = p.x - p_.wind_offset_m.x, y = p.y - p_.wind_offset_m.y;

    float w[4];
    weather_at(x * inv_weather_, y * inv_weather_, w);
    const double c_raw = k * (1.0 + p_.weather_variation * (2.0 * w[0] - 1.0));
    if (shape.fall > 0.0) return cirrus_density(x, y, f, c_raw, w);
    const double c = clamp01d(c_raw);
    if (c <= 0.0) return 0.0;
    if (shape.cells > 0.0) return cell_density(x, y, f, c, w, skip);
    // Towers: the local top, lower where the weather map's g is low.
    const double tower = clamp01d((w[1] - 0.3) / 0.4);
    const double f_top = 1.0 - shape.towers * (1.0 - tower);
    const double g = shape.gradient(f / f_top);
    if (g <= 0.0) return 0.0;

    // The base shape: domain-warped (half a tile at most), rotated and stretched.
    const double warp = 1.2 * p_.base_scale_m;
    const double xw = x + warp * (w[2] - 0.5), yw = y + warp * (w[3] - 0.5);
    const double sq = sqrt_stretch_;
    const double along = kStreakCos * xw + kStreakSin * yw, across = -kStreakSin * xw + kStreakCos * yw;
    const double zb = (h - p_.bottom_altitude_m + p_.evolution_m) * inv_base_;
    float b[2];  // the Perlin-Worley channel and fbm_w = 0.625 g + 0.25 b + 0.125 a
    base_at(along * inv_base_ / sq, across * inv_base_ * sq, zb, b);
    const double base = base_shape(b) * g;
    const double covered = clamp01d(remap(base, 1.0 - c, 1.0, 0.0, 1.0));
    if (covered <= 0.0) return 0.0;  // erosion only removes: skip the detail lookup
    if (p_.detail_strength <= 0.0) return covered;

    // Erosion: the detail noise, its lookup displaced by the curl noise (stronger low down).
    float cu[2];
    curl_.sample(x * inv_detail_ * 0.25, y * inv_detail_ * 0.25, 0.0, cu);
    const double amp = shape.curl * (1.0 - f);
    const double ax = kStreakCos * x + kStreakSin * y, ay = -kStreakSin * x + kStreakCos * y;
    const double zd = (h - p_.bottom_altitude_m + p_.evolution_m) * inv_detail_;
    float dt[4];  // [0]: 0.625 r + 0.25 g + 0.125 b of the detail texture
    detail_.sample(ax * inv_detail_ / sq + amp * cu[0], ay * inv_detail_ * sq + amp * cu[1], zd, dt);
    const double fbm_d = dt[0];
    const double modifier = fbm_d + (1.0 - 2.0 * fbm_d) * clamp01d(10.0 * f);  // mix(fbm, 1 - fbm, .)
    const double fade = shape.base_erosion > 0.0 ? clamp01d(f / shape.base_erosion) : 1.0;
    const double e = kMaxErosion * p_.detail_strength * (1.0 - covered) * modifier * fade;
    return clamp01d(remap(covered, e, 1.0, 0.0, 1.0));
}

// The footprint m of a cell or a streak at the (rotated, stretched) plane point (u, v) in
// base tiles: the base shape read at one height (every cell keeps its outline up the
// layer), remapped by the local coverage c (Schneider's remap). With m_peak (cells): also
// the footprint at the top of the cell the point lies in, m_peak >= m, from the peak map
// read with the same hex taps and remapped by the same c.
double ProceduralClouds::footprint(double u, double v, double c, double* m_peak) const {
    float b[3];
    slice_at(u, v, b);
    const double base = base_shape(b);
    const double m = clamp01d(remap(base, 1.0 - c, 1.0, 0.0, 1.0));
    if (m_peak) *m_peak = std::max(m, clamp01d(remap(b[2], 1.0 - c, 1.0, 0.0, 1.0)));
    return m;
}

// Cells (header): the footprint m from the base shape read at one height (every cell keeps
// its outline up the layer), a paraboloid heap over it narrowing upwards, its base the
// layer's bottom; the heap's surface pushed in by rounded lobes at three scales (the
// detail texture's Worley octaves, each biting as deep as its cells are wide between its
// balls: cauliflower), nothing at the base and most at the top; the density rises over
// kEdgeM inside the surface.
double ProceduralClouds::cell_density(double x, double y, double f, double c, const float* w,
                                      bool skip) const {
    const TypeShape& shape = shape_of(p_.cloud_type);
    const double tower = clamp01d((w[1] - 0.3) / 0.4);
    const double f_max = 1.0 - shape.towers * (1.0 - tower);
    // Above the highest dome this local top allows: clear air, before the footprint's read.
    if (skip && f >= cell_ceiling(f_max) + kBandMargin) return 0.0;
    // A gentle domain warp (its slope below one: a stronger one shreds the cells into swirls).
    const double warp = 0.3 * p_.base_scale_m;
    const double xw = x + warp * (w[2] - 0.5), yw = y + warp * (w[3] - 0.5);
    const double sq = sqrt_stretch_;
    const double along = kStreakCos * xw + kStreakSin * yw, across = -kStreakSin * xw + kStreakCos * yw;
    double m_peak = 0.0;
    const double m = footprint(along * inv_base_ / sq, across * inv_base_ * sq, c, &m_peak);
    if (m <= 0.0) return 0.0;
    // The heap: a dome over the cell's own footprint, f_top = H u^p, u = m / m_peak, p =
    // kDomeExponent. Near its top a cell's footprint is a quadratic bump (the Worley octaves
    // are 1 - d^2 about their feature points), m = m_peak (1 - r^2 / rho^2) with r the
    // distance from the top and rho the footprint's radius, so u = 1 - r^2 / rho^2 and every
    // cell is a rounded dome, level at its top whatever its size (with p < 1 steeper at the
    // foot than a paraboloid: the atlas's domes). A heap read from m alone, f_top = g(m),
    // keeps m's straight flanks under a peak that does not reach g's plateau: a tent. Its
    // radius rho = m_peak reach (reach about a Worley cell's radius at m = 1), its height
    // H = f_max v (2 - v), v = min(1, rho dome / (f_max thickness)): for the small cells
    // `dome` times their width (2 rho), a wider cell taller, up to the local top f_max (humilis:
    // broad and flattened).
    const double rho = m_peak * (kFootprintReach * p_.base_scale_m);
    const double v = heap_v(rho, f_max);
    const double height = f_max * v * (2.0 - v);
    const double u = std::min(1.0, m / m_peak);
    const double u_p = std::pow(u, kDomeExponent);  // u > 0: m > 0 and m_peak >= m
    const double f_top = height * u_p;
    if (f >= f_top) return 0.0;                           // the lobes only remove
    const double rise = clamp01d(f / shape.gradient.a1);  // the flat base
    // The distance in from the heap's surface, along its normal: the vertical one times the
    // cosine of the surface's slope (d(f_top thickness) / dr = 2 p H thickness u^(p - 1) r /
    // rho^2), at most the distance in from the footprint's edge, rho - r; so that the lobes
    // bite the steep sides as deep as the top.
    const double r_rel = std::sqrt(1.0 - u);  // r / rho
    const double slope = 2.0 * kDomeExponent * height * thickness_ * r_rel * (u_p / u) / rho;
    const double inside =
        std::min((f_top - f) * thickness_ / std::sqrt(1.0 + slope * slope), rho * (1.0 - r_rel));
    if (p_.detail_strength <= 0.0) return rise * clamp01d(inside / kEdgeM);
    // The lobes (cauliflower): the three Worley octaves of the detail texture read at half
    // its frequency (cells of detail_scale_m / 2, / 4, / 8), each 1 - W = d^2 (d the distance
    // to the octave's nearest feature point in its cells) scaled by its cell size, so that
    // the surface around each feature point is a paraboloid of radius of curvature
    // cell / (2 lobe): rounded bulges on bulges, creased between them (the atlas's
    // cauliflower, sprouting from the heap: Schneider's billows, GPU Pro 7 ch. 4, as a
    // displacement of the surface rather than a threshold of the density). Their weight
    // grows with the height in the heap (none at the flat base, most at the top).
    const double lobe = 2.0 * p_.detail_strength * shape.billow;
    const double cell0 = 0.5 * p_.detail_scale_m;
    const double weight = clamp01d(f / shape.base_erosion) * (0.3 + 0.7 * clamp01d(f / f_max));
    const double scale = lobe * cell0 * weight;
    // Deep inside, where no lobe reaches within kEdgeM of the point (each 1 - W is at most 1,
    // so the bite below is at most 1.39 scale): the depth clamps to 1 whatever the detail
    // noise reads, and the reads are skipped.
    if (skip && inside - 1.39 * scale >= kEdgeM + kBandMargin) return rise;
    // The lookup bent by the curl noise and shifted by the weather map's warp channels by up
    // to 1.5 periods (slowly, over the weather's scale), so that the periodic texture does
    // not repeat over a wide view.
    float cu[2];
    curl_.sample(x * inv_detail_ * 0.25, y * inv_detail_ * 0.25, 0.0, cu);
    const double amp = shape.curl;
    const double ax = kStreakCos * x + kStreakSin * y, ay = -kStreakSin * x + kStreakCos * y;
    const double h_m = f * thickness_ + p_.evolution_m;
    float d[4];  // fbm, then the Worley octaves at 4, 8, 16 cells per period
    detail_.sample(0.5 * ax * inv_detail_ / sq + amp * cu[0] + 1.5 * w[2],
                   0.5 * ay * inv_detail_ * sq + amp * cu[1] + 1.5 * w[3], 0.5 * h_m * inv_detail_, d);
    const double bite = scale * ((1.0 - d[1]) + 0.3 * (1.0 - d[2]) + 0.09 * (1.0 - d[3]));
    return rise * clamp01d((inside - bite) / kEdgeM);
}

// The heap's v (cell_density) for a cell of radius rho metres, under local top f_max.
double ProceduralClouds::heap_v(double rho, double f_max) const {
    return std::min(1.0, rho * shape_of(p_.cloud_type).dome / (f_max * thickness_));
}

// The heap's top for m_peak = 1: its height f_max v (2 - v) rises with v, v with rho, up to
// v = 1, and a cell's top is at most its height (u <= 1), so no cell reaches above it.
double ProceduralClouds::cell_ceiling(double f_max) const {
    const double v = heap_v(kFootprintReach * p_.base_scale_m, f_max);
    return f_max * v * (2.0 - v);
}

// Cirrus (header): heads of stretched tufts near the layer's top where the footprint m is
// high, fallstreaks hanging below them, longer under the stronger heads. The ice that falls
// from a head drifts with the wind's shear, whose direction turns with height: a point s
// of the way down from the heads lies under the head point xb = x - D(s), D(s) = base_scale
// (shear s e_along + hook s^2 e_across), a parabola in plan: the trail leaves the head along
// the streaks and bends across them (the atlas's uncinus: commas, hooks). The fibres are the
// trails of the head's grains: the detail noise (a fine 2D grain) read at xb, so that each
// grain of the head is drawn out along its own fall curve into a thin strand, many to a
// streak.
double ProceduralClouds::cirrus_density(double x, double y, double f, double c, const float* w) const {
    const TypeShape& shape = shape_of(p_.cloud_type);
    // Patches several kilometres across (the weather map read at 4 times its frequency,
    // elsewhere in its lattice): the strands come in tufts and bands, not over the whole sky.
    float wp[4];
    weather_at(4.0 * x * inv_weather_ + 0.31, 4.0 * y * inv_weather_ + 0.53, wp);
    c = clamp01d(c * clamp01d(2.5 * wp[0] - 0.75));
    if (c <= 0.0) return 0.0;
    // Curl bends (a tenth of a base tile at most), and the fall curve back to the head.
    float cu[2];
    curl_.sample(x * inv_base_ * 0.25, y * inv_base_ * 0.25, 0.0, cu);
    const double bend = 0.1 * p_.base_scale_m;
    const double warp = 0.3 * p_.base_scale_m;
    const double xw = x + warp * (w[2] - 0.5) + bend * cu[0], yw = y + warp * (w[3] - 0.5) + bend * cu[1];
    const double s = clamp01d((shape.gradient.a1 - f) / shape.gradient.a1);  // 0 at the heads
    // The hook's strength varies over the weather's scale (half to one and a half times).
    const double hook = shape.hook * (0.5 + wp[1]);
    const double along = kStreakCos * xw + kStreakSin * yw - thickness_ * shape.shear * s,
                 across = -kStreakSin * xw + kStreakCos * yw - thickness_ * hook * s * s;
    const double sq = sqrt_stretch_;
    const double m = footprint(along * inv_base_ / sq, across * inv_base_ * sq, c);
    if (m <= 0.0) return 0.0;
    // The head's trapezoid, and the fallstreak down to s = fall m, thinning downwards.
    const double head = shape.gradient(f);
    const double tail = s > 0.0 ? clamp01d((shape.fall * m - s) / 0.15) * (0.4 + 0.4 * (1.0 - s)) : 0.0;
    const double env = std::max(head, tail) * clamp01d(m / 0.2);
    if (env <= 0.0) return 0.0;
    if (p_.detail_strength <= 0.0) return env;
    // Fibres: the grain of the head (the detail fbm at one height, about two and a half times as long along
    // the streaks as across them) carried down its fall curve.
    float d[4];
    detail_.sample(0.25 * along * inv_detail_, 0.6 * across * inv_detail_, 0.5 * p_.evolution_m * inv_detail_,
                   d);
    const double strands = clamp01d(remap(d[0], 0.45, 0.75, 0.0, 1.0));
    return env * (1.0 - std::min(1.0, shape.fibres * p_.detail_strength) * (1.0 - strands));
}

// The hex-tiled reads (hex_read) of the weather map, the base texture and the footprints'
// slice (the base texture at z = evolution_m / base scale, with the peak map).
void ProceduralClouds::weather_at(double u, double v, float* w) const {
    hex_read(weather_, weather_mean_, u, v, 0.0, p_.seed * 0x100000001b3ULL + kWeatherTaps, w);
}

void ProceduralClouds::base_at(double u, double v, double z, float* b) const {
    hex_read(base_, base_mean_, u, v, z, p_.seed * 0x100000001b3ULL + kBaseTaps, b);
}

void ProceduralClouds::slice_at(double u, double v, float* b) const {
    const double mean[3] = {base_mean_[0], base_mean_[1], peak_mean_};
    hex_read(slice_, mean, u, v, 0.0, p_.seed * 0x100000001b3ULL + kBaseTaps, b);
}

// The shell between the bottom and top spheres, the ray stopped by the ground: the part of
// [0, t_max] inside the top sphere, minus the part inside the bottom sphere.
void ProceduralClouds::segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const {
    out.clear();
    if (!(p_.density_per_m > 0.0) || !(k_ > 0.0)) return;
    shell(ray, t_max, out);
}

// The shell's part of the ray (segments without the clear layer's early out).
void ProceduralClouds::shell(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const {
    out.clear();
    const double majorant = p_.density_per_m;
    const CentreOffset o(ray, centre_);
    double g0, g1;
    if (sphere_interval(o, p_.planet_radius_m, g0, g1) && g1 > 0.0)
        t_max = std::min(t_max, std::max(g0, 0.0));
    double a0, a1;
    if (!sphere_interval(o, p_.planet_radius_m + p_.top_altitude_m, a0, a1)) return;
    a0 = std::max(a0, 0.0);
    a1 = std::min(a1, t_max);
    if (!(a1 > a0)) return;
    double b0, b1;
    if (!sphere_interval(o, p_.planet_radius_m + p_.bottom_altitude_m, b0, b1) || b1 <= a0 || b0 >= a1) {
        out.push_back({a0, a1, majorant});
        return;
    }
    if (b0 > a0) out.push_back({a0, b0, majorant});
    if (b1 < a1) out.push_back({b1, a1, majorant});
}

double ProceduralClouds::feature_size_m() const {
    // One texel of the detail texture (32 per tile), the finest structure the layer has;
    // cirrus's strands, its grains drawn out down their tilted fall curves, are thinner
    // in the vertical than across: three quarters of a texel.
    const double texel = p_.detail_scale_m / 32.0;
    return shape_of(p_.cloud_type).fall > 0.0 ? 0.75 * texel : texel;
}

}  // namespace welkin
