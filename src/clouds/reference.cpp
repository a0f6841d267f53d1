// SPDX-License-Identifier: Apache-2.0
// Reference cloud lighting by path tracing; see clouds/reference.hpp.
#include "welkin/clouds/reference.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/atmosphere/observer.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/rng.hpp"

namespace welkin {

void CloudReferenceOptions::validate() const {
    scattering.validate();
    require_in_range("paths", paths, 1, 1 << 24);
    require_in_range("max_bounces", max_bounces, 1, 1 << 20);
    if (!(max_distance_m > 0.0 && max_distance_m <= 1e8))
        throw InvalidArgument("max_distance_m", fmt::format("must be in (0, 1e8] m, got {}", max_distance_m));
}

namespace {

constexpr double kFarAway = 1e8;  // shadow and scattered rays: to the end of every segment

// Ratio tracking: an unbiased estimate of exp(-integral of sigma_t) along the segments.
double ratio_tracking(const CloudDensity& density, const CloudRay& ray,
                      const std::vector<MajorantSegment>& segs, PathRng& rng) {
    double T = 1.0;
    for (const auto& g : segs) {
        double t = g.t0;
        while (true) {
            t -= std::log(rng.uniform_open0()) / g.majorant;
            if (t >= g.t1) break;
            T *= std::max(0.0, 1.0 - density.sigma_t(ray.at(t)) / g.majorant);
            if (T <= 0.0) return 0.0;
        }
    }
    return T;
}

// Delta tracking: the distance to the first real collision, or a negative value when the
// ray leaves every segment.
double delta_tracking(const CloudDensity& density, const CloudRay& ray,
                      const std::vector<MajorantSegment>& segs, PathRng& rng) {
    for (const auto& g : segs) {
        double t = g.t0;
        while (true) {
            t -= std::log(rng.uniform_open0()) / g.majorant;
            if (t >= g.t1) break;
            if (rng.uniform() * g.majorant < density.sigma_t(ray.at(t))) return t;
        }
    }
    return -1.0;
}

}  // namespace

CloudReferenceResult render_clouds_reference(const CloudDensity& density, const CloudIllumination& light,
                                             const glm::dvec3& origin, std::span<const glm::dvec3> directions,
                                             const CloudReferenceOptions& options, Progress* progress) {
    options.validate();
    for (int a = 0; a < 3; ++a) require_finite(fmt::format("origin[{}]", a), origin[a]);
    validate_directions(directions);
    const std::size_t n = directions.size(), nc = light.channels();
    CloudReferenceResult result;
    result.channels = nc;
    result.radiance.assign(n * nc, 0.0f);
    result.radiance_error.assign(n * nc, 0.0f);
    result.transmittance.assign(n, 1.0f);
    result.transmittance_error.assign(n, 0.0f);
    result.depth_m.assign(n, 0.0f);
    const glm::dvec3 s = light.sun_direction();
    const CloudScattering& sc = options.scattering;
    const int paths = options.paths;
    std::atomic<std::uint64_t> truncated{0};

    ProgressTracker tracker(progress, n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1), [&](const auto& range) {
        std::vector<MajorantSegment> segs, view_segs;
        std::vector<float> e(nc), above(nc), below(nc);
        std::vector<double> path_l(nc), sum(nc), sum2(nc);
        for (std::size_t r = range.begin(); r != range.end(); ++r) {
            const glm::dvec3 d0 = glm::normalize(directions[r]);
            const CloudRay view{origin, d0};
            density.segments(view, options.max_distance_m, view_segs);
            std::fill(sum.begin(), sum.end(), 0.0);
            std::fill(sum2.begin(), sum2.end(), 0.0);
            double t_sum = 0.0, t_sum2 = 0.0, depth_num = 0.0, depth_den = 0.0;
            std::uint64_t cut = 0;
            for (int p = 0; p < paths && !view_segs.empty(); ++p) {
                PathRng rng(options.seed, r, std::uint64_t(p));
                // Transmittance of the view ray (ratio tracking).
                const double T = ratio_tracking(density, view, view_segs, rng);
                t_sum += T;
                t_sum2 += T * T;
                // The radiance path.
                std::fill(path_l.begin(), path_l.end(), 0.0);
                CloudRay ray = view;
                double t = delta_tracking(density, ray, view_segs, rng);
                if (t >= 0.0) {
                    depth_num += t;
                    depth_den += 1.0;
                }
                double beta = 1.0;
                int bounce = 0;
                glm::dvec3 last{};
                while (t >= 0.0) {
                    if (bounce >= options.max_bounces) {
                        ++cut;
                        break;
                    }
                    const glm::dvec3 x = ray.at(t);
                    last = x;
                    beta *= sc.albedo;
                    ++bounce;
                    // Next-event estimation of the sun.
                    const CloudRay shadow{x, s};
                    density.segments(shadow, kFarAway, segs);
                    const double Ts = segs.empty() ? 1.0 : ratio_tracking(density, shadow, segs, rng);
                    if (Ts > 0.0) {
                        light.sun_irradiance(x, e.data());
                        const double w = beta * Ts * sc.phase(glm::dot(ray.direction, s));
                        for (std::size_t c = 0; c < nc; ++c) path_l[c] += w * e[c];
                    }
                    // Scatter.
                    const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                    ray = {x, sc.phase.sample(ray.direction, u0, u1, u2)};
                    density.segments(ray, kFarAway, segs);
                    t = segs.empty() ? -1.0 : delta_tracking(density, ray, segs, rng);
                }
                if (bounce > 0 && t < 0.0) {
                    // Left the cloud: the sky at the last vertex, from the hemisphere the
                    // path leaves into.
                    light.sky_radiance(last, above.data(), below.data());
                    const bool up = glm::dot(ray.direction, light.zenith(last)) > 0.0;
                    for (std::size_t c = 0; c < nc; ++c) path_l[c] += beta * (up ? above[c] : below[c]);
                }
                for (std::size_t c = 0; c < nc; ++c) {
                    sum[c] += path_l[c];
                    sum2[c] += path_l[c] * path_l[c];
                }
            }
            if (!view_segs.empty()) {
                const double np = paths;
                const auto se = [&](double s1, double s2) {
                    const double mean = s1 / np;
                    return np > 1 ? std::sqrt(std::max(0.0, (s2 / np - mean * mean) / (np - 1))) : 0.0;
                };
                for (std::size_t c = 0; c < nc; ++c) {
                    result.radiance[r * nc + c] = float(sum[c] / np);
                    result.radiance_error[r * nc + c] = float(se(sum[c], sum2[c]));
                }
                result.transmittance[r] = float(t_sum / np);
                result.transmittance_error[r] = float(se(t_sum, t_sum2));
                result.depth_m[r] = depth_den > 0.0 ? float(depth_num / depth_den) : 0.0f;
            }
            truncated += cut;
            tracker.advance();
        }
    });
    tracker.finish();
    result.truncated_fraction = double(truncated.load()) / (double(n) * paths);
    return result;
}

}  // namespace welkin
