// A procedural cloud layer; see procedural_clouds.hpp.
#include "welkin/clouds/procedural.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>
#include <mutex>

#include <fmt/format.h>
#include <glm/geometric.hpp>

#include "welkin/base/error.hpp"

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

// The segment [t0, t1] of the ray inside the sphere of radius r about c: roots of
// t^2 + 2 b t + q = 0, b = d . (o - c), q = |o - c|^2 - r^2 = (|o - c| - r)(|o - c| + r)
// (factored so that a point near the sphere keeps its digits). False if it misses.
bool sphere_interval(const CloudRay& ray, const glm::dvec3& c, double r, double& t0, double& t1) {
    const glm::dvec3 oc = ray.origin - c;
    const double l = glm::length(oc);
    const double b = glm::dot(ray.direction, oc);
    const double q = (l - r) * (l + r);
    const double disc = b * b - q;
    if (disc < 0.0) return false;
    const double s = std::sqrt(disc);
    // Numerically stable pair: the root of larger magnitude first, the other from q.
    const double big = b > 0.0 ? -b - s : -b + s;
    const double other = big != 0.0 ? q / big : 0.0;
    t0 = std::min(big, other);
    t1 = std::max(big, other);
    return true;
}

}  // namespace

void CloudLayerParams::validate() const {
    require_in_range("bottom_altitude_m", bottom_altitude_m, 0.0, 20000.0, "m");
    require_in_range("top_altitude_m", top_altitude_m, 0.0, 20000.0, "m");
    if (!(top_altitude_m > bottom_altitude_m))
        throw InvalidArgument("top_altitude_m", fmt::format("must be above bottom_altitude_m ({} m), got {} m",
                                                            bottom_altitude_m, top_altitude_m));
    require_in_range("coverage", coverage, 0.0, 1.0);
    require_in_range("cloud_type", cloud_type, 0.0, 1.0);
    require_in_range("density_per_m", density_per_m, 0.0, 10.0, "m^-1");
    require_in_range("base_scale_m", base_scale_m, 10.0, 1e6, "m");
    require_in_range("detail_scale_m", detail_scale_m, 1.0, 1e6, "m");
    require_in_range("weather_scale_m", weather_scale_m, 10.0, 1e7, "m");
    require_in_range("detail_strength", detail_strength, 0.0, 1.0);
    require_in_range("weather_variation", weather_variation, 0.0, 1.0);
    require_in_range("type_variation", type_variation, 0.0, 1.0);
    require_finite("wind_offset_m[0]", wind_offset_m.x);
    require_finite("wind_offset_m[1]", wind_offset_m.y);
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
    detail_ = PeriodicTexture<1>(m, m, m);
    for (int k = 0; k < m; ++k)
        for (int j = 0; j < m; ++j)
            for (int i = 0; i < m; ++i) {
                const glm::vec4 v = nd.at(i, j, k);
                detail_.at(i, j, k)[0] = 0.625f * v.r + 0.25f * v.g + 0.125f * v.b;
            }
    const auto& nw = noise_->weather;
    const int q = nw.size();
    weather_ = PeriodicTexture<2>(q, q, 1);
    for (int j = 0; j < q; ++j)
        for (int i = 0; i < q; ++i) {
            weather_.at(i, j, 0)[0] = nw.at(i, j, 0).r;
            weather_.at(i, j, 0)[1] = nw.at(i, j, 0).g;
        }
    inv_weather_ = 1.0 / p_.weather_scale_m;
    inv_base_ = 1.0 / p_.base_scale_m;
    inv_detail_ = 1.0 / p_.detail_scale_m;
}

// Trapezoids (a0, a1, a2, a3): 0 below a0, rising to 1 at a1, 1 to a2, falling to 0 at a3.
double ProceduralClouds::height_gradient(double type, double f) {
    if (!(f >= 0.0 && f <= 1.0)) return 0.0;
    struct Trapezoid {
        double a0, a1, a2, a3;
        double operator()(double x) const {
            return clamp01d(remap(x, a0, a1, 0.0, 1.0)) * clamp01d(remap(x, a2, a3, 1.0, 0.0));
        }
    };
    constexpr Trapezoid stratus{0.0, 0.08, 0.15, 0.3};
    constexpr Trapezoid stratocumulus{0.0, 0.15, 0.35, 0.6};
    constexpr Trapezoid cumulus{0.0, 0.1, 0.65, 1.0};
    const double t = clamp01d(type);
    if (t <= 0.5) {
        const double w = t / 0.5;
        return (1.0 - w) * stratus(f) + w * stratocumulus(f);
    }
    const double w = (t - 0.5) / 0.5;
    return (1.0 - w) * stratocumulus(f) + w * cumulus(f);
}

double ProceduralClouds::sigma_t(const glm::dvec3& p) const {
    const double h = glm::length(p - centre_) - p_.planet_radius_m;
    const double thickness = p_.top_altitude_m - p_.bottom_altitude_m;
    const double f = (h - p_.bottom_altitude_m) / thickness;
    if (!(f > 0.0 && f < 1.0) || p_.coverage <= 0.0 || p_.density_per_m <= 0.0) return 0.0;
    const double x = p.x - p_.wind_offset_m.x, y = p.y - p_.wind_offset_m.y;

    float w[2];
    weather_.sample(x * inv_weather_, y * inv_weather_, 0.0, w);
    const double c = p_.coverage * clamp01d(1.0 + p_.weather_variation * (2.0 * w[0] - 1.0));
    const double t = clamp01d(p_.cloud_type + p_.type_variation * (2.0 * w[1] - 1.0));
    const double g = height_gradient(t, f);
    if (c <= 0.0 || g <= 0.0) return 0.0;

    const double zb = (h - p_.bottom_altitude_m) * inv_base_;
    float b[2];  // the Perlin-Worley channel and fbm_w = 0.625 g + 0.25 b + 0.125 a
    base_.sample(x * inv_base_, y * inv_base_, zb, b);
    const double fbm_w = b[1];
    const double base = remap(b[0], -(1.0 - fbm_w), 1.0, 0.0, 1.0) * g;
    const double covered = clamp01d(remap(base, 1.0 - c, 1.0, 0.0, 1.0)) * c;
    if (covered <= 0.0) return 0.0;  // erosion only removes: skip the detail lookup

    const double zd = (h - p_.bottom_altitude_m) * inv_detail_;
    float fbm_d_f;  // 0.625 r + 0.25 g + 0.125 b of the detail texture
    detail_.sample(x * inv_detail_, y * inv_detail_, zd, &fbm_d_f);
    const double fbm_d = fbm_d_f;
    const double modifier = fbm_d + (1.0 - 2.0 * fbm_d) * clamp01d(10.0 * f);  // mix(fbm, 1 - fbm, .)
    const double density = remap(covered, p_.detail_strength * modifier, 1.0, 0.0, 1.0);
    return p_.density_per_m * clamp01d(density);
}

// The shell between the bottom and top spheres, the ray stopped by the ground: the part of
// [0, t_max] inside the top sphere, minus the part inside the bottom sphere.
void ProceduralClouds::segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const {
    out.clear();
    const double majorant = p_.density_per_m * p_.coverage;
    if (!(majorant > 0.0)) return;
    double g0, g1;
    if (sphere_interval(ray, centre_, p_.planet_radius_m, g0, g1) && g1 > 0.0) t_max = std::min(t_max, std::max(g0, 0.0));
    double a0, a1;
    if (!sphere_interval(ray, centre_, p_.planet_radius_m + p_.top_altitude_m, a0, a1)) return;
    a0 = std::max(a0, 0.0);
    a1 = std::min(a1, t_max);
    if (!(a1 > a0)) return;
    double b0, b1;
    if (!sphere_interval(ray, centre_, p_.planet_radius_m + p_.bottom_altitude_m, b0, b1) || b1 <= a0 || b0 >= a1) {
        out.push_back({a0, a1, majorant});
        return;
    }
    if (b0 > a0) out.push_back({a0, b0, majorant});
    if (b1 < a1) out.push_back({b1, a1, majorant});
}

double ProceduralClouds::feature_size_m() const {
    // One texel of the detail texture (32 per tile), the finest structure the layer has.
    return p_.detail_scale_m / 32.0;
}

}  // namespace welkin
