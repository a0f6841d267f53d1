// SPDX-License-Identifier: Apache-2.0
// Fast cloud lighting; see clouds/lighting.hpp.
#include "welkin/clouds/lighting.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "welkin/atmosphere/observer.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/rng.hpp"
#include "welkin/clouds/depth_grid.hpp"
#include "welkin/clouds/diffusion.hpp"

namespace welkin {

void CloudScattering::validate() const {
    require_in_range("albedo", albedo, 0.0, 1.0);
    phase.validate();
}

void CloudLightingOptions::validate() const {
    scattering.validate();
    require_in_range("max_steps", max_steps, 1, 4096);
    require_in_range("light_steps", light_steps, 1, 256);
    require_in_range("ambient_steps", ambient_steps, 0, 256);
    if (!(light_distance_m > 0.0 && light_distance_m <= 1e6))
        throw InvalidArgument("light_distance_m",
                              fmt::format("must be in (0, 1e6] m, got {}", light_distance_m));
    require_in_range("octaves", octaves, 1, 16);
    for (const auto& [name, v] : {std::pair{"octave_extinction", octave_extinction},
                                  std::pair{"octave_contribution", octave_contribution},
                                  std::pair{"octave_eccentricity", octave_eccentricity}})
        if (!(v > 0.0 && v <= 1.0)) throw InvalidArgument(name, fmt::format("must be in (0, 1], got {}", v));
    if (!(min_transmittance >= 0.0 && min_transmittance < 1.0))
        throw InvalidArgument("min_transmittance",
                              fmt::format("must be in [0, 1), got {}", min_transmittance));
    if (!(max_distance_m > 0.0 && max_distance_m <= 1e8))
        throw InvalidArgument("max_distance_m", fmt::format("must be in (0, 1e8] m, got {}", max_distance_m));
    require_in_range("tail_transmittance", tail_transmittance, 0.0, 1.0);
    require_in_range("shadow_grid_spacing_m", shadow_grid_spacing_m, 0.0, 1e5, "m");
    require_in_range("ray_spread_rad", ray_spread_rad, 0.0, 1.0, "rad");
    require_in_range("ray_width_m", ray_width_m, 0.0, 1e6, "m");
}

CloudResult render_clouds(const CloudDensity& density, const CloudIllumination& light,
                          const glm::dvec3& origin, std::span<const glm::dvec3> directions,
                          const CloudLightingOptions& options, Progress* progress) {
    for (int a = 0; a < 3; ++a) require_finite(fmt::format("origin[{}]", a), origin[a]);
    return render_clouds(density, light, std::span<const glm::dvec3>(&origin, 1), directions, {}, options,
                         progress);
}

namespace {

constexpr int kSideLevels = 3;  // the side grids' levels above the sun grid's

// The march of every ray (grid_width == 0), or of a grid of rays (rows of grid_width) with
// upsampling (the header's render_clouds_grid).
CloudResult march(const CloudDensity& density, const CloudIllumination& light,
                  std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                  std::span<const double> max_distances, const CloudLightingOptions& options,
                  Progress* progress, std::uint64_t first_ray_index, int grid_width,
                  const CloudUpsampling& up) {
    options.validate();
    validate_directions(directions);
    const std::size_t n = directions.size(), nc = light.channels();
    if (origins.size() != 1 && origins.size() != n)
        throw InvalidArgument("origins", fmt::format("must hold 1 or {} points (one per direction), got {}",
                                                     n, origins.size()));
    for (std::size_t i = 0; i < origins.size(); ++i)
        for (int a = 0; a < 3; ++a) require_finite(fmt::format("origins[{}][{}]", i, a), origins[i][a]);
    if (!max_distances.empty() && max_distances.size() != n)
        throw InvalidArgument("max_distances",
                              fmt::format("must be empty or hold {} values (one per direction), "
                                          "got {}",
                                          n, max_distances.size()));
    for (std::size_t i = 0; i < max_distances.size(); ++i)
        if (!(max_distances[i] >= 0.0))
            throw InvalidArgument(fmt::format("max_distances[{}]", i),
                                  fmt::format("must be >= 0 m, got {}", max_distances[i]));
    CloudResult result;
    result.channels = nc;
    result.radiance.assign(n * nc, 0.0f);
    result.transmittance.assign(n, 1.0f);
    result.depth_m.assign(n, 0.0f);

    const glm::dvec3 s = light.sun_direction();
    const CloudScattering& sc = options.scattering;
    const int octaves = options.octaves;
    // Per-octave weights b^i, extinction scales a^i, eccentricity scales c^i.
    std::vector<double> ob(octaves), oa(octaves), oc(octaves);
    for (int i = 0; i < octaves; ++i) {
        ob[i] = std::pow(options.octave_contribution, i);
        oa[i] = std::pow(options.octave_extinction, i);
        oc[i] = std::pow(options.octave_eccentricity, i);
    }

    // The diffusion decay rate of sky light into an absorbing cloud, per unit optical depth
    // (see the header): 0 for albedo 1.
    const double mean_g = sc.phase.mean_cosine();
    const double kappa = std::sqrt(std::max(0.0, 3.0 * (1.0 - sc.albedo) * (1.0 - sc.albedo * mean_g)));

    // The optical-depth grids (clouds/depth_grid.hpp) towards the sun and, when the sky
    // light decays (albedo < 1), towards the local zenith; filled lazily by the rays.
    const double h0 =
        options.shadow_grid_spacing_m > 0.0 ? options.shadow_grid_spacing_m : 2.0 * density.feature_size_m();
    const bool ambient_decay = options.ambient_steps > 0 && kappa > 0.0;
    std::unique_ptr<OpticalDepthGrid> sun_grid, sky_grid, anti_grid, side_grid, back_grid;
    // The cloud's chord across the sun line, for the diffusion's sides (diffusion.hpp): along
    // the horizontal direction normal to the sun (x where the sun is at the zenith), both
    // ways, on a grid three levels coarser than the sun's (the chord is a large-scale
    // quantity: it sets the leak, not the shading's detail).
    const glm::dvec3 across = [&] {
        const glm::dvec3 c = glm::cross(s, glm::dvec3(0.0, 0.0, 1.0));
        return glm::length(c) > 1e-6 ? glm::normalize(c) : glm::dvec3(1.0, 0.0, 0.0);
    }();
    const bool sides = options.sides;
    // Orders >= 2: the delta-Eddington slab along the sun line (clouds/diffusion.hpp) or
    // the octaves; either way octaves = 1 is single scattering.
    const bool diffusion = options.multiple_scattering == CloudMultipleScattering::diffusion && octaves > 1;
    const bool sized = octaves > 1 && (diffusion || options.octave_optical_size);
    const SimilarityScaling similarity(sc.albedo, mean_g);
    if (options.shadow_grid) {
        sun_grid = std::make_unique<OpticalDepthGrid>(
            density, [s](const glm::dvec3&) { return s; }, h0, options.light_distance_m, options.light_steps);
        if (sized)
            anti_grid = std::make_unique<OpticalDepthGrid>(
                density, [s](const glm::dvec3&) { return -s; }, h0, options.light_distance_m,
                options.light_steps);
        if (diffusion && sides) {
            side_grid = std::make_unique<OpticalDepthGrid>(
                density, [across](const glm::dvec3&) { return across; }, h0, options.light_distance_m,
                options.light_steps);
            back_grid = std::make_unique<OpticalDepthGrid>(
                density, [across](const glm::dvec3&) { return -across; }, h0, options.light_distance_m,
                options.light_steps);
        }
        if (ambient_decay)
            sky_grid = std::make_unique<OpticalDepthGrid>(
                density, [&light](const glm::dvec3& p) { return light.zenith(p); }, h0,
                options.light_distance_m, options.ambient_steps);
    }

    struct Scratch {
        std::vector<MajorantSegment> segs, light_segs;
        std::vector<float> sun, sky;
        std::vector<double> acc;
        OpticalDepthGrid::Cursor sun_cursor, sky_cursor, anti_cursor, side_cursor, back_cursor;
    };
    // Marches ray r into the result.
    const auto march_ray = [&](std::size_t r, Scratch& scratch) {
        auto& [segs, light_segs, sun, sky, acc, sun_cursor, sky_cursor, anti_cursor, side_cursor,
               back_cursor] = scratch;
        sun.resize(nc), sky.resize(nc), acc.resize(nc);
        {
            const glm::dvec3 d = glm::normalize(directions[r]);
            const CloudRay ray{origins[origins.size() == 1 ? 0 : r], d};
            const double t_end = max_distances.empty() ? options.max_distance_m
                                                       : std::min(max_distances[r], options.max_distance_m);
            density.segments(ray, t_end, segs);
            double total = 0.0;
            for (const auto& g : segs) total += g.t1 - g.t0;
            if (!(total > 0.0)) return;
            const double dt_target = std::max(total / options.max_steps, 0.5 * density.feature_size_m());
            // The grids' levels at distance t: no finer than the view step nor the ray's
            // footprint (the header); re-read when the footprint has doubled.
            const bool footprint = sun_grid && (options.ray_spread_rad > 0.0 || options.ray_width_m > 0.0);
            int sun_level = 0, side_level = 0;
            double next_level_t = -1.0;  // the footprint's level holds below this t
            const auto set_levels = [&](double t) {
                const double w = options.ray_width_m + options.ray_spread_rad * t;
                sun_level = sun_grid ? sun_grid->level_for(std::max(dt_target, w)) : 0;
                side_level = std::min(sun_level + kSideLevels, OpticalDepthGrid::kMaxLevels - 1);
                next_level_t =
                    footprint && options.ray_spread_rad > 0.0
                        ? (sun_grid->spacing_m(sun_level + 1) - options.ray_width_m) / options.ray_spread_rad
                        : std::numeric_limits<double>::infinity();
            };
            set_levels(0.0);
            PathRng rng(options.seed, first_ray_index + r, 0, 0x636c6f7564ULL);
            const double u = options.jitter ? rng.uniform() : 0.5;
            // Phase values of the octaves: nu = d . s is the same at every sample.
            const double nu = glm::dot(d, s);
            std::vector<double> phase(octaves);
            for (int i = 0; i < octaves; ++i) phase[i] = sc.phase(nu, oc[i]);
            const double phase2 = diffusion ? sc.phase.twice(nu) : 0.0;

            std::fill(acc.begin(), acc.end(), 0.0);
            double T = 1.0, depth_sum = 0.0, opacity_sum = 0.0;
            bool done = false;
            for (const auto& g : segs) {
                if (done) break;
                const int steps = std::max(1, int(std::ceil((g.t1 - g.t0) / dt_target - 1e-9)));
                const double dt = (g.t1 - g.t0) / steps;
                for (int k = 0, span = 1; k < steps; k += span) {
                    // The dim tail: below tail_transmittance a step spans up to 8 base steps,
                    // about tail_transmittance / T of them (whole steps, the same jitter u).
                    // Empty space keeps the base step: a longer step there can pass over a
                    // thin wisp (tests/cpp/test_cloud_fast_vs_reference.cpp measures it).
                    const bool dim = T < options.tail_transmittance;
                    span =
                        dim ? std::min({steps - k, 8, std::max(1, int(options.tail_transmittance / T))}) : 1;
                    const double h = span * dt;
                    const double t = g.t0 + k * dt + u * h;
                    const glm::dvec3 x = ray.at(t);
                    const double sigma_t = density.sigma_t(x);
                    if (!(sigma_t > 0.0)) continue;
                    if (footprint && t >= next_level_t) set_levels(t);
                    // The cloud's optical depth from x along dir: from the grid when there is
                    // one, else by its own march of `steps` steps.
                    const auto depth_along = [&](const std::unique_ptr<OpticalDepthGrid>& grid,
                                                 OpticalDepthGrid::Cursor& cursor, int level,
                                                 const glm::dvec3& dir, int steps) {
                        return grid ? grid->tau(x, level, cursor)
                                    : march_optical_depth(density, {x, dir}, options.light_distance_m, steps,
                                                          light_segs);
                    };
                    const double tau_sun =
                        depth_along(sun_grid, sun_cursor, sun_level, s, options.light_steps);
                    // The cloud's depth away from the sun along the sun line through x: the
                    // slab's thickness (diffusion), or the octaves' optical size f =
                    // 1 - exp(-tau_line), octave i weighted by f^i (see the header).
                    const double tau_anti =
                        sized ? depth_along(anti_grid, anti_cursor, sun_level, -s, options.light_steps) : 0.0;
                    double sun_w = 0.0;
                    if (diffusion) {
                        // Single scattering plus the forward-scattered and diffuse parts.
                        double tau_side = std::numeric_limits<double>::infinity();
                        if (sides)
                            tau_side =
                                depth_along(side_grid, side_cursor, side_level, across, options.light_steps) +
                                depth_along(back_grid, back_cursor, side_level, -across, options.light_steps);
                        sun_w =
                            sun_source(similarity, tau_sun, tau_anti, tau_side, nu, mean_g, phase[0], phase2);
                    } else {
                        const double f = sized ? 1.0 - std::exp(-(tau_sun + tau_anti)) : 1.0;
                        double fi = 1.0;
                        for (int i = 0; i < octaves; ++i, fi *= f)
                            sun_w += ob[i] * fi * std::exp(-oa[i] * tau_sun) * phase[i];
                    }
                    double sky_w = 1.0;
                    if (ambient_decay) {
                        const double tau_up = depth_along(sky_grid, sky_cursor, sun_level, light.zenith(x),
                                                          options.ambient_steps);
                        sky_w = std::exp(-kappa * tau_up);
                    }
                    light.sun_irradiance(x, sun.data());
                    light.ambient_radiance(x, sky.data());
                    // Energy-conserving step: S / sigma_t = albedo (sun + sky terms).
                    const double step_opacity = 1.0 - std::exp(-sigma_t * h);
                    const double w = T * step_opacity * sc.albedo;
                    for (std::size_t c = 0; c < nc; ++c) acc[c] += w * (sun[c] * sun_w + sky[c] * sky_w);
                    depth_sum += t * T * step_opacity;
                    opacity_sum += T * step_opacity;
                    T *= 1.0 - step_opacity;
                    if (T < options.min_transmittance) {
                        done = true;
                        break;
                    }
                }
            }
            for (std::size_t c = 0; c < nc; ++c) result.radiance[r * nc + c] = float(acc[c]);
            result.transmittance[r] = float(T);
            result.depth_m[r] = opacity_sum > 0.0 ? float(depth_sum / opacity_sum) : 0.0f;
        }
    };
    tbb::enumerable_thread_specific<Scratch> scratches;
    // Marches the rays `which` (all when null).
    const auto march_rays = [&](const std::vector<std::size_t>* which, ProgressTracker& tracker) {
        const std::size_t count = which ? which->size() : n;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
            Scratch& scratch = scratches.local();  // warm tile caches across a thread's chunks
            for (std::size_t k = range.begin(); k != range.end(); ++k) {
                march_ray(which ? (*which)[k] : k, scratch);
                tracker.advance();
            }
        });
    };
    if (grid_width <= 0 || up.stride <= 1) {
        ProgressTracker tracker(progress, n);
        march_rays(nullptr, tracker);
        tracker.finish();
        return result;
    }

    // The grid, refined as a quadtree (the header's CloudUpsampling): march the rays at
    // every stride-th column and row (and the last ones), then, level by level, split each
    // block whose four corner rays disagree at its midpoints, marching the new corners.
    // Each pixel belongs to the block whose half-open rectangle [x0, x1) x [y0, y1) holds it
    // (the last column and row closed), so it is interpolated once, from the corners of the
    // smallest block around it.
    const int W = grid_width, H = int(n / std::size_t(grid_width));
    CloudGridInterpolation& grid = result.interpolation;
    grid.width = W, grid.height = H;
    grid.marched.assign(n, 0);
    std::vector<std::size_t> todo;
    const auto mark = [&](int x, int y) {
        const std::size_t p = std::size_t(y) * std::size_t(W) + std::size_t(x);
        if (!grid.marched[p]) grid.marched[p] = 1, todo.push_back(p);
    };
    std::vector<int> xs, ys;  // the coarse lattice
    for (int i = 0; i < W; i += up.stride) xs.push_back(i);
    if (xs.back() != W - 1) xs.push_back(W - 1);
    for (int j = 0; j < H; j += up.stride) ys.push_back(j);
    if (ys.back() != H - 1) ys.push_back(H - 1);
    using Block = CloudGridInterpolation::Block;
    std::vector<Block> blocks;
    for (std::size_t b = 0; b + 1 < ys.size(); ++b)
        for (std::size_t a = 0; a + 1 < xs.size(); ++a)
            blocks.push_back({xs[a], ys[b], xs[a + 1], ys[b + 1]});
    for (int y : ys)
        for (int x : xs) mark(x, y);
    ProgressTracker tracker(progress, n);
    std::size_t marched = 0;
    // Whether the four corner rays of a block agree (transmittances within
    // up.transmittance_tolerance, each channel's radiance within up.radiance_tolerance of
    // the largest).
    const auto smooth = [&](const Block& b) {
        const std::array<std::size_t, 4> q = b.corners(W);
        float tmin = 2.0f, tmax = -1.0f;
        for (std::size_t a : q) {
            tmin = std::min(tmin, result.transmittance[a]);
            tmax = std::max(tmax, result.transmittance[a]);
        }
        if (tmax - tmin > up.transmittance_tolerance) return false;
        for (std::size_t c = 0; c < nc; ++c) {
            float lmin = 1e30f, lmax = 0.0f;
            for (std::size_t a : q) {
                lmin = std::min(lmin, result.radiance[a * nc + c]);
                lmax = std::max(lmax, result.radiance[a * nc + c]);
            }
            if (lmax - lmin > up.radiance_tolerance * lmax) return false;
        }
        return true;
    };
    // Whether the block spans more than up.max_block_size_m at its farthest cloud: the
    // angle between its diagonal's corner rays times that depth.
    const auto too_wide = [&](const Block& b) {
        const std::array<std::size_t, 4> q = b.corners(W);
        float depth = 0.0f;
        for (std::size_t a : q) depth = std::max(depth, result.depth_m[a]);
        if (!(depth > 0.0f)) return false;
        const double chord =
            std::max(glm::length(glm::normalize(directions[q[0]]) - glm::normalize(directions[q[3]])),
                     glm::length(glm::normalize(directions[q[1]]) - glm::normalize(directions[q[2]])));
        return chord * depth > up.max_block_size_m;
    };
    while (!todo.empty()) {
        std::sort(todo.begin(), todo.end());  // neighbouring rays together, whatever the order found
        march_rays(&todo, tracker);
        marched += todo.size();
        todo.clear();
        std::vector<Block> split;
        for (const Block& b : blocks) {
            if (b.x1 - b.x0 <= 1 && b.y1 - b.y0 <= 1) continue;  // every pixel it owns is a corner
            if ((b.x1 - b.x0 <= up.finest && b.y1 - b.y0 <= up.finest) || (smooth(b) && !too_wide(b))) {
                grid.blocks.push_back(b);
                continue;
            }
            // Split along each axis at least two pixels long, marching the new corners.
            const int xm = b.x1 - b.x0 >= 2 ? (b.x0 + b.x1) / 2 : -1;
            const int ym = b.y1 - b.y0 >= 2 ? (b.y0 + b.y1) / 2 : -1;
            const int cx[3] = {b.x0, xm, b.x1}, cy[3] = {b.y0, ym, b.y1};
            for (int j = 0; j < 3; ++j)
                for (int i = 0; i < 3; ++i)
                    if (cx[i] >= 0 && cy[j] >= 0) mark(cx[i], cy[j]);
            for (int j = 0; j < 2; ++j)
                for (int i = 0; i < 2; ++i) {
                    const int x0 = xm < 0 ? (i == 0 ? b.x0 : -1) : cx[i], x1 = xm < 0 ? b.x1 : cx[i + 1];
                    const int y0 = ym < 0 ? (j == 0 ? b.y0 : -1) : cy[j], y1 = ym < 0 ? b.y1 : cy[j + 1];
                    if (x0 >= 0 && y0 >= 0) split.push_back({x0, y0, x1, y1});
                }
        }
        blocks = std::move(split);
    }
    // Every other ray from its block's corners; the depth weighted by opacity, where there
    // is cloud.
    grid.interpolate(result.radiance, nc);
    grid.interpolate(result.transmittance, 1);
    grid.for_each_interpolated([&](std::size_t p, const std::size_t q[4], const double w[4]) {
        double dsum = 0.0, dw = 0.0;
        for (int a = 0; a < 4; ++a) {
            const double o = w[a] * (1.0 - result.transmittance[q[a]]);
            dsum += o * result.depth_m[q[a]];
            dw += o;
        }
        result.depth_m[p] = dw > 0.0 ? float(dsum / dw) : 0.0f;
    });
    tracker.advance(n - marched);
    tracker.finish();
    return result;
}

}  // namespace

CloudResult render_clouds(const CloudDensity& density, const CloudIllumination& light,
                          std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                          std::span<const double> max_distances, const CloudLightingOptions& options,
                          Progress* progress, std::uint64_t first_ray_index) {
    return march(density, light, origins, directions, max_distances, options, progress, first_ray_index, 0,
                 {});
}

CloudResult render_clouds_grid(const CloudDensity& density, const CloudIllumination& light,
                               const glm::dvec3& origin, std::span<const glm::dvec3> directions, int width,
                               const CloudLightingOptions& options, const CloudUpsampling& upsampling,
                               Progress* progress, std::uint64_t first_ray_index) {
    for (int a = 0; a < 3; ++a) require_finite(fmt::format("origin[{}]", a), origin[a]);
    upsampling.validate();
    if (width < 1 || directions.size() % std::size_t(width) != 0)
        throw InvalidArgument("width", fmt::format("must divide the number of directions ({}), got {}",
                                                   directions.size(), width));
    const int stride = directions.size() / std::size_t(width) < 2 || width < 2 ? 1
                       : upsampling.stride == 0 ? std::clamp(width / CloudUpsampling::kAutoColumns, 1, 16)
                                                : upsampling.stride;
    CloudUpsampling up = upsampling;
    up.stride = stride;
    return march(density, light, std::span<const glm::dvec3>(&origin, 1), directions, {}, options, progress,
                 first_ray_index, width, up);
}

void CloudGridInterpolation::interpolate(std::span<float> values, std::size_t channels) const {
    if (all_marched()) return;
    if (values.size() != std::size_t(width) * std::size_t(height) * channels)
        throw InvalidArgument("values", fmt::format("must hold {} x {} x {} values, got {}", width, height,
                                                    channels, values.size()));
    for_each_interpolated([&](std::size_t p, const std::size_t q[4], const double w[4]) {
        for (std::size_t c = 0; c < channels; ++c) {
            double v = 0.0;
            for (int a = 0; a < 4; ++a) v += w[a] * values[q[a] * channels + c];
            values[p * channels + c] = float(v);
        }
    });
}

double angle_between_rays(const glm::dvec3& a, const glm::dvec3& b) {
    // 2 asin(|u - v| / 2): accurate for the small angles between neighbouring pixels.
    const double chord = glm::length(glm::normalize(a) - glm::normalize(b));
    return 2.0 * std::asin(std::min(1.0, 0.5 * chord));
}

void CloudUpsampling::validate() const {
    require_in_range("stride", stride, 0, 16);
    require_in_range("finest", finest, 1, 16);
    require_in_range("max_block_size_m", max_block_size_m, 0.0, 1e7, "m");
    require_in_range("transmittance_tolerance", transmittance_tolerance, 0.0, 1.0);
    require_in_range("radiance_tolerance", radiance_tolerance, 0.0, 1.0);
}

}  // namespace welkin
