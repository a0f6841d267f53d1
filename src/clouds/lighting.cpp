// SPDX-License-Identifier: Apache-2.0
// Fast cloud lighting; see clouds/lighting.hpp.
#include "welkin/clouds/lighting.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/concurrent_unordered_map.h>
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
    require_in_range("surface_cut", surface_cut, 1, 64);
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

// The sides' grid (levels_for): its level above the sun grid's, and its lines' spacing in
// the vertical, in its own cells (a quarter of the sun grid's cell).
constexpr int kSideLevels = 2;
constexpr double kSideVertical = 1.0 / 16.0;
constexpr int kSkyLevels = 1;  // the zenith and nadir grids' level above the sun grid's
// sin 15 deg: the lowest sun whose anti-sun depth is on a grid turned to it (SampleLight).
constexpr double kTurnedAntiSunMinSin = 0.2588;
// The closest the sun grid's lines come across the vertical (sun_cross_spacing), in cells.
constexpr double kMinSunCross = 1.0 / 8.0;

// The spacing, in cells, of the sun grid's lines along its climbing cross axis e_2 (the
// axis that is vertical when the sun is on the horizon; depth_grid.hpp, "Cross
// spacing"), for the sun at elevation el. Below a flat face of the cloud (a deck's top
// seen against a low sun, a cell's crown), the next line, c h away along e_2, starts c h
// cos(el) higher, and its path to the face is c h cos(el) / sin(el) shorter: the depth
// steps by sigma_t c h cot(el) from line to line, where a 45-degree sun's steps by
// sigma_t h. Interpolated across its kink at the face, such a profile reads deep, and the
// lit rim of a deck's top seen against a low sun comes out dark (docs/validation.md, "The
// sun grid's lines under a low sun"). c = tan(el) keeps the 45-degree step, at most one
// cell (a higher sun's lines run up the cloud, its faces along them) and at least
// kMinSunCross (the lines, and the vertices marched, grow as 1 / c).
double sun_cross_spacing(double sin_el) {
    const double s = std::clamp(sin_el, 0.0, 1.0);
    return std::clamp(s / std::sqrt(std::max(1e-12, 1.0 - s * s)), kMinSunCross, 1.0);
}

// The input checks of a march: one origin or one per direction, finite; max_distances
// empty or one non-negative length per direction.
void check_rays(std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                std::span<const double> max_distances) {
    validate_directions(directions);
    const std::size_t n = directions.size();
    if (origins.size() != 1 && origins.size() != n)
        throw InvalidArgument("origins", fmt::format("must hold 1 or {} points (one per direction), got {}",
                                                     n, origins.size()));
    for (std::size_t i = 0; i < origins.size(); ++i)
        for (int a = 0; a < 3; ++a)  // the name formatted only for the error: a frame has millions
            if (!std::isfinite(origins[i][a]))
                require_finite(fmt::format("origins[{}][{}]", i, a), origins[i][a]);
    if (!max_distances.empty() && max_distances.size() != n)
        throw InvalidArgument("max_distances",
                              fmt::format("must be empty or hold {} values (one per direction), "
                                          "got {}",
                                          n, max_distances.size()));
    for (std::size_t i = 0; i < max_distances.size(); ++i)
        if (!(max_distances[i] >= 0.0))
            throw InvalidArgument(fmt::format("max_distances[{}]", i),
                                  fmt::format("must be >= 0 m, got {}", max_distances[i]));
}

// The optical-depth grids (clouds/depth_grid.hpp) a march reads: towards the sun, away
// from it (the sun line's other half, for the diffusion's slab or the octaves' optical
// size), both ways across the sun line (the diffusion's sides) and, when the sky light
// decays (albedo < 1) or two skies light it, towards the local zenith and nadir. Each is
// null where the march does not need it or marches a ray per sample instead (shadow_grid
// off). Filled lazily by the rays.
struct ShadowGrids {
    std::unique_ptr<OpticalDepthGrid> sun, anti, side, sky, ground;
};

// The per-sample light of the header: the sun's weight (single and multiple scattering)
// and the sky's, from the optical depths along the grids' directions.
class SampleLight {
public:
    struct Cursors {
        std::vector<MajorantSegment> light_segs;  // a shadow march's segments (no grid)
        OpticalDepthGrid::Cursor sun, sky, ground, anti, side;
    };
    // The grid levels a sample reads (the sun's, its other half's, the sides').
    struct Levels {
        int sun = 0, side = 0, sky = 0;  // the anti-sun grid reads the sun's level
        bool near = false;               // the sun grid's near field: the rays about a cell apart or more
    };
    // The phase values of one ray's direction: nu = d . s is the same at every sample.
    struct RayPhase {
        glm::dvec3 d{0.0};  // the view ray's direction
        double nu = 0.0, twice = 0.0;
        std::vector<double> octave;
    };

    SampleLight(const CloudDensity& density, const CloudIllumination& light,
                const CloudLightingOptions& options)
        : density_(density),
          light_(light),
          options_(options),
          s_(light.sun_direction()),
          mean_g_(options.scattering.phase.mean_cosine()),
          similarity_(options.scattering.albedo, mean_g_) {
        const CloudScattering& sc = options.scattering;
        const int octaves = options.octaves;
        // Per-octave weights b^i, extinction scales a^i, eccentricity scales c^i.
        ob_.resize(octaves), oa_.resize(octaves), oc_.resize(octaves);
        for (int i = 0; i < octaves; ++i) {
            ob_[i] = std::pow(options.octave_contribution, i);
            oa_[i] = std::pow(options.octave_extinction, i);
            oc_[i] = std::pow(options.octave_eccentricity, i);
        }
        // The diffusion decay rate of sky light into an absorbing cloud, per unit optical
        // depth (see the header): 0 for albedo 1.
        kappa_ = std::sqrt(std::max(0.0, 3.0 * (1.0 - sc.albedo) * (1.0 - sc.albedo * mean_g_)));
        ambient_decay_ = options.ambient_steps > 0 && kappa_ > 0.0;
        // A sky brighter above the horizon than below: the depths up and down set the mix.
        two_skies_ = !light.uniform_sky();
        transport_ = 1.0 - sc.albedo * mean_g_;
        // The cloud's chord across the sun line, for the diffusion's sides (diffusion.hpp):
        // along the horizontal direction normal to the sun (x where the sun is at the
        // zenith), both ways.
        const glm::dvec3 c = glm::cross(s_, glm::dvec3(0.0, 0.0, 1.0));
        across_ = glm::length(c) > 1e-6 ? glm::normalize(c) : glm::dvec3(1.0, 0.0, 0.0);
        // Orders >= 2: the delta-Eddington slab along the sun line (clouds/diffusion.hpp)
        // or the octaves; either way octaves = 1 is single scattering.
        diffusion_ = options.multiple_scattering == CloudMultipleScattering::diffusion && octaves > 1;
        sized_ = octaves > 1 && (diffusion_ || options.octave_optical_size);
        if (options.shadow_grid) build_grids();
    }

    const OpticalDepthGrid* sun_grid() const { return grids_.sun.get(); }

    // The levels for a footprint of `width` metres: no finer than it. The depths towards
    // and away from the sun (the single scattering's shadow, the slab's thickness) are read
    // at the sun's level (one level coarser, the depth away from the sun lost 2 % on
    // altocumulus cells; docs/validation.md). The depths up and down set the two skies' mix,
    // a large-scale quantity of the diffuse light: one level coarser. The sides' chord, a
    // horizontal line's depth over kilometres both ways, changes slowly across the ground
    // and fast up the cloud (a deck's base, a thin layer's cells): its lines kSideLevels
    // coarser across the ground and along the line, and kSideVertical of that apart in the
    // vertical (build_grids). Read on cubic cells one level coarser than the sun's, it came
    // out too long at a deck's base and too short across thin cells (docs/validation.md,
    // "The sides' chord").
    Levels levels_for(double width) const {
        Levels lv;
        lv.sun = grids_.sun ? grids_.sun->level_for(width) : 0;
        lv.side = std::min(lv.sun + kSideLevels, OpticalDepthGrid::kMaxLevels - 1);
        lv.sky = std::min(lv.sun + kSkyLevels, OpticalDepthGrid::kMaxLevels - 1);
        return lv;
    }

    void ray_phase(const glm::dvec3& d, RayPhase& ph) const {
        const CloudScattering& sc = options_.scattering;
        ph.d = d;
        ph.nu = glm::dot(d, s_);
        ph.octave.resize(options_.octaves);
        for (int i = 0; i < options_.octaves; ++i) ph.octave[i] = sc.phase(ph.nu, oc_[i]);
        ph.twice = diffusion_ ? sc.phase.twice(ph.nu) : 0.0;
    }

    // The sky's weights at a sample: the factors of sigma_s L_above and sigma_s L_below in
    // the source (the sun's, of sigma_s E: sun_weight).
    struct SkyWeights {
        double above = 1.0, below = 0.0;
    };
    // Whether the sky's weights are the two skies' (sky_weights): what else they depend on
    // (the density, the sample, the view ray, the options) a kept ray keeps.
    bool two_skies() const { return two_skies_; }

    // The sun's weight at sample x.
    double sun_weight(const glm::dvec3& x, const Levels& lv, const RayPhase& ph, Cursors& cur) const {
        const int steps = options_.light_steps;
        const double tau_sun = depth_along(grids_.sun, cur.sun, lv.sun, x, s_, steps, cur, lv.near);
        // The cloud's depth away from the sun along the sun line through x: the slab's
        // thickness (diffusion), or the octaves' optical size f = 1 - exp(-tau_line),
        // octave i weighted by f^i (see the header).
        const double tau_anti = sized_ ? depth_along(grids_.anti, cur.anti, lv.sun, x, -s_, steps, cur) : 0.0;
        double sun_w = 0.0;
        if (diffusion_) {
            // Single scattering plus the forward-scattered and diffuse parts.
            double tau_side = std::numeric_limits<double>::infinity();
            if (options_.sides)
                // The grid reads both ways along its lines; without it, a march each way.
                tau_side = grids_.side
                               ? grids_.side->tau(x, lv.side, cur.side)
                               : march_optical_depth(density_, {x, across_}, options_.light_distance_m, steps,
                                                     cur.light_segs) +
                                     march_optical_depth(density_, {x, -across_}, options_.light_distance_m,
                                                         steps, cur.light_segs);
            sun_w =
                sun_source(similarity_, tau_sun, tau_anti, tau_side, ph.nu, mean_g_, ph.octave[0], ph.twice);
        } else {
            const double f = sized_ ? 1.0 - std::exp(-(tau_sun + tau_anti)) : 1.0;
            double fi = 1.0;
            for (int i = 0; i < options_.octaves; ++i, fi *= f)
                sun_w += ob_[i] * fi * std::exp(-oa_[i] * tau_sun) * ph.octave[i];
        }
        return sun_w;
    }

    // The sky's weights at sample x: they do not depend on the sun.
    SkyWeights sky_weights(const glm::dvec3& x, const Levels& lv, const RayPhase& ph, Cursors& cur) const {
        SkyWeights w;
        if (two_skies_ && options_.ambient_steps == 0) {
            w.above = w.below = 0.5;  // no depths: the two skies' mean, as in a thin cloud
        } else if (two_skies_) {
            const glm::dvec3 z = light_.zenith(x);
            // Read one level coarser (levels_for): the mix is set by the depths to the cloud's
            // faces, a large-scale quantity the diffuse light smooths.
            const double tau_up = depth_along(grids_.sky, cur.sky, lv.sky, x, z, options_.ambient_steps, cur);
            const double tau_down =
                depth_along(grids_.ground, cur.ground, lv.sky, x, -z, options_.ambient_steps, cur);
            // Eddington's conservative slab between the two skies (see the header): the
            // diffuse field is linear in the scaled depth, Marshak's conditions at the faces;
            // its net flux, scattered with the phase's mean cosine towards the viewer.
            const double D = transport_ * (tau_up + tau_down) + 4.0 / 3.0;
            const double flux = mean_g_ * glm::dot(ph.d, z) / D;
            w.below = std::max(0.0, (transport_ * tau_up + 2.0 / 3.0) / D - flux);
            w.above = std::max(0.0, (transport_ * tau_down + 2.0 / 3.0) / D + flux);
            if (ambient_decay_) {
                w.above *= std::exp(-kappa_ * tau_up);
                w.below *= std::exp(-kappa_ * tau_down);
            }
        } else if (ambient_decay_) {
            const double tau_up =
                depth_along(grids_.sky, cur.sky, lv.sun, x, light_.zenith(x), options_.ambient_steps, cur);
            w.above = std::exp(-kappa_ * tau_up);
        }
        return w;
    }

private:
    void build_grids() {
        const double h0 = options_.shadow_grid_spacing_m > 0.0 ? options_.shadow_grid_spacing_m
                                                               : 2.0 * density_.feature_size_m();
        const auto along = [&](const glm::dvec3& dir, int steps) {
            return std::make_unique<OpticalDepthGrid>(density_, dir, h0, options_.light_distance_m, steps);
        };
        grids_.sun = along(s_, options_.light_steps);
        // Where the rays' footprint is known (an image's neighbouring rays): the first two of
        // the sun grid's cells marched per sample, the rest read one level coarser, on
        // vertices the neighbouring rays share (depth_grid.hpp, "Near field").
        if (options_.ray_spread_rad > 0.0 || options_.ray_width_m > 0.0) grids_.sun->set_near_field(1, 2);
        const double sin_el = glm::dot(s_, light_.zenith(glm::dvec3(0.0)));
        grids_.sun->set_cross_spacing(1.0, sun_cross_spacing(sin_el));
        // The depth away from the sun: a grid turned to -s, whose first cell a sample
        // marches itself as on the sun grid. Read at the view samples, inside a layer whose
        // flat base kinks it (chord, below) and whose density ramps up over its lower part:
        // without the near field, the interpolation's error there, which depends on where
        // a slanted line of vertices meets the base, beat into streaks along the sun's
        // azimuth on an even deck seen from below. Under a low sun the lines run nearly
        // along the base, the near field's cell rises too little to reach it, and the
        // streaks come back as wedges: there a grid of world axes, a march per vertex
        // (docs/validation.md, "Chord-scaled depth grids").
        if (sized_ && sin_el >= kTurnedAntiSunMinSin) {
            grids_.anti = along(-s_, options_.light_steps);
            grids_.anti->set_near_field(1, 2);
        } else if (sized_) {
            grids_.anti = std::make_unique<OpticalDepthGrid>(
                density_, [d = -s_](const glm::dvec3&) { return d; }, h0, options_.light_distance_m,
                options_.light_steps);
        }
        if (diffusion_ && options_.sides) {
            grids_.side = along(across_, options_.light_steps);
            grids_.side->set_both_ways(true);  // the chord both ways, one walk per line
            // Lines a cell apart along the ground, kSideVertical of one in the vertical: the
            // grid's first axis is horizontal, its second vertical (the line is horizontal).
            grids_.side->set_cross_spacing(1.0, kSideVertical);
        }
        // The depths up and down: grids aligned with the zenith at the world's origin, whose
        // vertices on one vertical share a walk, as the sun's do (docs/validation.md, "The
        // light from below"). Over a curved planet the line at a point d from the origin
        // leans d / R from its local vertical, and its depth through a flat layer is
        // 1 / cos(d / R) times the vertical one: 0.1 % at 300 km, the farthest a layer seen
        // from the ground reaches.
        const glm::dvec3 up = light_.zenith(glm::dvec3(0.0));
        if (ambient_decay_ || (two_skies_ && options_.ambient_steps > 0))
            grids_.sky = along(up, options_.ambient_steps);
        if (two_skies_ && options_.ambient_steps > 0) grids_.ground = along(-up, options_.ambient_steps);
        // Every grid interpolates the mean extinction along its lines, the depth's kink at
        // the density's faces (a layer's flat base and top) taken exactly from the majorant
        // segments (depth_grid.hpp, "Chord"): interpolated across, that kink brightened an
        // overcast deck by several per cent (docs/validation.md, "Chord-scaled depth grids").
        for (auto* grid : {&grids_.sun, &grids_.anti, &grids_.side, &grids_.sky, &grids_.ground})
            if (*grid) (*grid)->set_chord_scaled(true);
    }

    // The cloud's optical depth from x along dir: from the grid when there is one (its near
    // field, if set, unless near_field is false), else by its own march of `steps` steps.
    double depth_along(const std::unique_ptr<OpticalDepthGrid>& grid, OpticalDepthGrid::Cursor& cursor,
                       int level, const glm::dvec3& x, const glm::dvec3& dir, int steps, Cursors& cur,
                       bool near_field = true) const {
        return grid ? grid->tau(x, level, cursor, near_field)
                    : march_optical_depth(density_, {x, dir}, options_.light_distance_m, steps,
                                          cur.light_segs);
    }

    const CloudDensity& density_;
    const CloudIllumination& light_;
    const CloudLightingOptions& options_;
    glm::dvec3 s_, across_;
    double mean_g_;  // the phase's mean cosine g
    SimilarityScaling similarity_;
    std::vector<double> ob_, oa_, oc_;
    double kappa_ = 0.0, transport_ = 1.0;  // transport_: 1 - albedo g, the diffusion's scaling
    bool ambient_decay_ = false, two_skies_ = false, diffusion_ = false, sized_ = false;
    ShadowGrids grids_;
};

// The march of view rays (the header's steps) into a CloudResult.
class RayMarcher {
public:
    RayMarcher(const CloudDensity& density, const CloudIllumination& light, const SampleLight& sample_light,
               std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
               std::span<const double> max_distances, const CloudLightingOptions& options,
               std::uint64_t first_ray_index, CloudResult& result, double ray_spacing = 1.0)
        : density_(density),
          light_(light),
          origins_(origins),
          directions_(directions),
          max_distances_(max_distances),
          options_(options),
          first_ray_index_(first_ray_index),
          ray_spacing_(ray_spacing),
          result_(result),
          sample_light_(sample_light) {}

    // Marches the rays `which` (all when null), in parallel.
    void march_rays(const std::vector<std::size_t>* which, ProgressTracker& tracker) {
        const std::size_t count = which ? which->size() : directions_.size();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& range) {
            Scratch& scratch = scratches_.local();  // warm tile caches across a thread's chunks
            for (std::size_t k = range.begin(); k != range.end(); ++k) {
                march_ray(which ? (*which)[k] : k, scratch);
                tracker.advance();
            }
        });
    }

private:
    struct Scratch {
        std::vector<MajorantSegment> segs;
        std::vector<float> sun, above, below;
        std::vector<double> acc;
        SampleLight::Cursors cursors;
        SampleLight::RayPhase phase;
        std::vector<CloudViewCache::Sample> stored;  // the ray's samples, for the view cache
    };

    // The footprint along one ray at distance t: the distance to the neighbouring pixels'
    // rays (the header), and to the neighbouring marched rays, `spacing` pixels apart. The
    // grids' levels: no finer than the view step nor the marched rays' footprint (the
    // grids' cells, which those rays share), re-read when the footprint has doubled.
    class RayLevels {
    public:
        RayLevels(const SampleLight& light, const CloudLightingOptions& o, double spacing, double dt)
            : light_(light), o_(o), spacing_(spacing), dt_(dt), sun_grid_(light.sun_grid()) {
            footprint_ = sun_grid_ && (o.ray_spread_rad > 0.0 || o.ray_width_m > 0.0);
            set(0.0);
        }
        double pixel_at(double t) const { return o_.ray_width_m + o_.ray_spread_rad * t; }
        const SampleLight::Levels& at(double t) {
            if (footprint_ && t >= next_t_) set(t);
            // The sun grid's near field where the rays are about a cell apart or more;
            // denser rays share the vertices of their own level already.
            levels_.near = footprint_ && spacing_ * pixel_at(t) >= 0.5 * sun_grid_->spacing_m(levels_.sun);
            return levels_;
        }

    private:
        void set(double t) {
            levels_ = light_.levels_for(std::max(dt_, spacing_ * pixel_at(t)));
            next_t_ =
                footprint_ && o_.ray_spread_rad > 0.0
                    ? (sun_grid_->spacing_m(levels_.sun + 1) / spacing_ - o_.ray_width_m) / o_.ray_spread_rad
                    : std::numeric_limits<double>::infinity();
        }
        const SampleLight& light_;
        const CloudLightingOptions& o_;
        double spacing_, dt_;
        const OpticalDepthGrid* sun_grid_;
        bool footprint_ = false;
        SampleLight::Levels levels_;
        double next_t_ = -1.0;  // the footprint's level holds below this t
    };

    // Marches ray r into the result.
    void march_ray(std::size_t r, Scratch& scratch) const {
        const std::size_t nc = light_.channels();
        auto& [segs, sun, above, below, acc, cursors, phase, stored] = scratch;
        sun.resize(nc), above.resize(nc), below.resize(nc), acc.resize(nc);
        const glm::dvec3 d = glm::normalize(directions_[r]);
        const CloudRay ray{origins_[origins_.size() == 1 ? 0 : r], d};
        // The ray's samples from the view cache, or the segments its march steps through.
        CloudViewCache* const cache = options_.view_cache.get();
        const std::uint64_t key = first_ray_index_ + r;
        const CloudViewCache::Ray* const kept = cache ? cache->find(key) : nullptr;
        double total = 0.0;
        if (!kept) {
            const double t_end = max_distances_.empty()
                                     ? options_.max_distance_m
                                     : std::min(max_distances_[r], options_.max_distance_m);
            density_.segments(ray, t_end, segs);
            for (const auto& g : segs) total += g.t1 - g.t0;
        }
        if (kept ? kept->samples.empty() : !(total > 0.0)) {
            if (cache && !kept) cache->store(key, {});
            return;
        }
        const double half_feature = 0.5 * density_.feature_size_m();
        const double dt_target = kept ? kept->dt_target : std::max(total / options_.max_steps, half_feature);
        RayLevels levels(sample_light_, options_, ray_spacing_, dt_target);
        sample_light_.ray_phase(d, phase);
        stored.clear();

        std::fill(acc.begin(), acc.end(), 0.0);
        double T = 1.0, depth_sum = 0.0, opacity_sum = 0.0;
        const double albedo = options_.scattering.albedo;
        bool alive = true;  // false once T < min_transmittance: the ray stops
        // A kept ray's sky weights hold under a sky of the same kind (two skies or one).
        const bool kept_sky = kept && kept->two_skies == sample_light_.two_skies();
        // The sample at t (density sigma_t at x) of a step h long; k: its kept sample.
        const auto light_sample = [&](double t, double h, double sigma_t, const glm::dvec3& x,
                                      const CloudViewCache::Sample* k) {
            const SampleLight::Levels& lv = levels.at(t);
            const double sun_w = sample_light_.sun_weight(x, lv, phase, cursors);
            const SampleLight::SkyWeights sky = k && kept_sky
                                                    ? SampleLight::SkyWeights{k->above, k->below}
                                                    : sample_light_.sky_weights(x, lv, phase, cursors);
            if (cache && !kept) stored.push_back({t, h, sigma_t, sky.above, sky.below});
            light_.sun_irradiance(x, sun.data());
            light_.sky_radiance(x, above.data(), below.data());
            // Energy-conserving step: S / sigma_t = albedo (sun + sky terms).
            const double step_opacity = 1.0 - std::exp(-sigma_t * h);
            const double w = T * step_opacity * albedo;
            for (std::size_t c = 0; c < nc; ++c)
                acc[c] += w * (sun[c] * sun_w + above[c] * sky.above + below[c] * sky.below);
            depth_sum += t * T * step_opacity;
            opacity_sum += T * step_opacity;
            T *= 1.0 - step_opacity;
            alive = T >= options_.min_transmittance;
        };
        if (kept) {
            for (const auto& k : kept->samples) light_sample(k.t, k.h, k.sigma_t, ray.at(k.t), &k);
        } else {
            const auto integrate = [&](double t, double h, double sigma_t, const glm::dvec3& x) {
                light_sample(t, h, sigma_t, x, nullptr);
            };
            march_samples(ray, r, segs, dt_target, half_feature, levels, T, alive, integrate);
            if (cache) cache->store(key, {dt_target, sample_light_.two_skies(), stored});
        }
        for (std::size_t c = 0; c < nc; ++c) result_.radiance[r * nc + c] = float(acc[c]);
        result_.transmittance[r] = float(T);
        result_.depth_m[r] = opacity_sum > 0.0 ? float(depth_sum / opacity_sum) : 0.0f;
    }

    // The march's steps along ray r through its segments (the header's "Steps", "The
    // surface", "The dim tail"): integrate(t, h, sigma_t, x) at each sample that finds
    // cloud, while `alive` (integrate updates T and alive).
    template <class Integrate>
    void march_samples(const CloudRay& ray, std::size_t r, const std::vector<MajorantSegment>& segs,
                       double dt_target, double half_feature, const RayLevels& levels, const double& T,
                       const bool& alive, Integrate& integrate) const {
        PathRng rng(options_.seed, first_ray_index_ + r, 0, 0x636c6f7564ULL);
        const double u = options_.jitter ? rng.uniform() : 0.5;
        // The step [a, a + dt) cut into n, each sample at the same fraction u of its own
        // step; whether any sample was in a cloud.
        const auto cut = [&](double a, double dt, int n) {
            const double h = dt / n;
            bool cloud = false;
            for (int j = 0; j < n && alive; ++j) {
                const double t = a + (j + u) * h;
                const glm::dvec3 x = ray.at(t);
                const double sigma_t = density_.sigma_t(x);
                if (!(sigma_t > 0.0)) continue;
                cloud = true;
                integrate(t, h, sigma_t, x);
            }
            return cloud;
        };
        for (const auto& g : segs) {
            if (!alive) break;
            const int steps = std::max(1, int(std::ceil((g.t1 - g.t0) / dt_target - 1e-9)));
            const double dt = (g.t1 - g.t0) / steps;
            // How many pieces the base step at t is cut into at a surface (the header's "The
            // surface"): none shorter than half the feature size nor the pixel's footprint.
            const auto pieces = [&](double t) {
                const double fine = std::max(half_feature, levels.pixel_at(t));
                return std::clamp(int(std::min(dt / fine, 64.0)), 1, options_.surface_cut);
            };
            bool was_cut = false, in_cloud = false;  // the last step: cut; cut and cloudy
            for (int k = 0, span = 1; k < steps && alive; k += span) {
                // The dim tail: below tail_transmittance a step spans up to 8 base steps,
                // about tail_transmittance / T of them (whole steps, the same jitter u).
                // Empty space keeps the base step: a longer step there can pass over a thin
                // wisp (tests/cpp/test_cloud_fast_vs_reference.cpp measures it).
                const bool dim = T < options_.tail_transmittance;
                span = dim ? std::min({steps - k, 8, std::max(1, int(options_.tail_transmittance / T))}) : 1;
                const double h = span * dt;
                const double a = g.t0 + k * dt;
                const double t = a + u * h;
                const int n = dim ? 1 : pieces(t);
                const bool cut_before = was_cut;
                was_cut = n > 1 && in_cloud;
                if (was_cut) {  // still in the cloud, or one step out of it
                    in_cloud = cut(a, dt, n);
                    continue;
                }
                in_cloud = false;
                const glm::dvec3 x = ray.at(t);
                const double sigma_t = density_.sigma_t(x);
                if (!(sigma_t > 0.0)) continue;
                if (n == 1) {
                    integrate(t, h, sigma_t, x);
                    continue;
                }
                // A cloud's near surface: the step before (empty at its sample, so it added
                // nothing) and this one, cut. This sample is not used: a cut's samples sit
                // at u of their own steps.
                if (k > 0 && !cut_before) cut(a - dt, dt, pieces(t - dt));
                if (alive) in_cloud = cut(a, dt, n);
                was_cut = true;
            }
        }
    }

    const CloudDensity& density_;
    const CloudIllumination& light_;
    std::span<const glm::dvec3> origins_, directions_;
    std::span<const double> max_distances_;
    const CloudLightingOptions& options_;
    std::uint64_t first_ray_index_;
    double ray_spacing_;  // pixels between neighbouring marched rays: the footprint's factor
    CloudResult& result_;
    const SampleLight& sample_light_;
    tbb::enumerable_thread_specific<Scratch> scratches_;
};

using Block = CloudGridInterpolation::Block;

// Whether the four corner rays of a block agree (transmittances within
// up.transmittance_tolerance, each channel's radiance within up.radiance_tolerance of the
// largest).
bool corners_agree(const CloudResult& result, const Block& b, int width, const CloudUpsampling& up) {
    const std::array<std::size_t, 4> q = b.corners(width);
    const std::size_t nc = result.channels;
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
}

// Whether the block spans more than up.max_block_size_m at its farthest cloud: the angle
// between its diagonal's corner rays times that depth, plus their origins' distance (the
// parallel rays of an orthographic camera).
bool too_wide(const CloudResult& result, std::span<const glm::dvec3> origins,
              std::span<const glm::dvec3> directions, const Block& b, int width, const CloudUpsampling& up) {
    const std::array<std::size_t, 4> q = b.corners(width);
    float depth = 0.0f;
    for (std::size_t a : q) depth = std::max(depth, result.depth_m[a]);
    if (!(depth > 0.0f)) return false;
    const auto spread = [&](std::size_t i, std::size_t j) {
        const double apart = origins.size() == 1 ? 0.0 : glm::length(origins[i] - origins[j]);
        return glm::length(glm::normalize(directions[i]) - glm::normalize(directions[j])) * depth + apart;
    };
    return std::max(spread(q[0], q[3]), spread(q[1], q[2])) > up.max_block_size_m;
}

// Whether every ray of the block (its closed rectangle) is of one kind: unbounded, or
// ending within CloudUpsampling::kLengthTolerance of the others (header). Always true
// without lengths.
bool lengths_agree(std::span<const double> max_distances, const Block& b, int width) {
    if (max_distances.empty()) return true;
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    for (int y = b.y0; y <= b.y1; ++y)
        for (int x = b.x0; x <= b.x1; ++x) {
            const double d = max_distances[std::size_t(y) * std::size_t(width) + std::size_t(x)];
            lo = std::min(lo, d), hi = std::max(hi, d);
        }
    if (std::isinf(lo)) return true;  // every ray unbounded
    return !std::isinf(hi) && hi - lo <= CloudUpsampling::kLengthTolerance * lo;
}

// Splits b at its midpoints along each axis at least two pixels long into `split`,
// calling mark(x, y) for each corner of the new blocks.
template <class Mark>
void split_block(const Block& b, std::vector<Block>& split, Mark&& mark) {
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

// Every unmarched ray from its block's corners; the depth weighted by opacity, where there
// is cloud.
void interpolate_unmarched(CloudResult& result) {
    const CloudGridInterpolation& grid = result.interpolation;
    grid.interpolate(result.radiance, result.channels);
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
}

// How many times wider than tall, in pixels, a block between rows y0 and y1 is made so that
// it is about square in angle (the header's CloudUpsampling): the angle between
// neighbouring rows (rows y0 and y1's over y1 - y0) over that between neighbouring columns
// (at the middle column, of row y0 or y1, whichever is the larger), rounded down to a power
// of two, at most kMaxAspect. From those two rows alone, so that a band of a frame cut at
// its lattice rows has the frame's blocks. An equirect's rows near a pole are circles of
// 2 pi cos(elevation): there its columns are 1 / cos(elevation) times closer than its rows.
// A pinhole camera's are about as close (1); parallel rays (an orthographic camera) have
// no angle between them (1).
int block_aspect(std::span<const glm::dvec3> directions, int width, int y0, int y1) {
    constexpr int kMaxAspect = 32;
    if (width < 2) return 1;
    const int xc = (width - 1) / 2;
    const auto angle = [&](int xa, int ya, int xb, int yb) {
        return angle_between_rays(directions[std::size_t(ya) * std::size_t(width) + std::size_t(xa)],
                                  directions[std::size_t(yb) * std::size_t(width) + std::size_t(xb)]);
    };
    const double down = angle(xc, y0, xc, y1) / double(y1 - y0);
    if (!(down > 0.0)) return 1;
    const double across = std::max(angle(xc, y0, xc + 1, y0), angle(xc, y1, xc + 1, y1));
    const double ratio = across > 0.0 ? down / across : std::numeric_limits<double>::infinity();  // a pole
    int aspect = 1;
    while (aspect < kMaxAspect && 2.0 * aspect <= ratio) aspect *= 2;
    return aspect;
}

// The grid, refined as a quadtree (the header's CloudUpsampling): march the rays at every
// stride-th row and every (stride x the block row's aspect)-th column (and the last ones),
// then, level by level, split each block whose four corner rays disagree at its midpoints,
// marching the new corners. Each pixel belongs to the block whose half-open rectangle
// [x0, x1) x [y0, y1) holds it (the last column and row closed), so it is interpolated
// once, from the corners of the smallest block around it.
void march_refined(RayMarcher& marcher, CloudResult& result, std::span<const glm::dvec3> origins,
                   std::span<const glm::dvec3> directions, std::span<const double> max_distances, int width,
                   const CloudUpsampling& up, Progress* progress) {
    const std::size_t n = directions.size();
    const int W = width, H = int(n / std::size_t(width));
    CloudGridInterpolation& grid = result.interpolation;
    grid.width = W, grid.height = H;
    grid.marched.assign(n, 0);
    std::vector<std::size_t> todo;
    const auto mark = [&](int x, int y) {
        const std::size_t p = std::size_t(y) * std::size_t(W) + std::size_t(x);
        if (!grid.marched[p]) grid.marched[p] = 1, todo.push_back(p);
    };
    std::vector<int> ys;  // the coarse lattice's rows
    for (int j = 0; j < H; j += up.stride) ys.push_back(j);
    if (ys.back() != H - 1) ys.push_back(H - 1);
    // Per row, the aspect of the blocks of its lattice row: the finest block there is
    // `finest` rows tall and finest x aspect columns wide.
    std::vector<int> aspect(std::size_t(H), 1);
    std::vector<Block> blocks;
    for (std::size_t b = 0; b + 1 < ys.size(); ++b) {
        const int m = block_aspect(directions, W, ys[b], ys[b + 1]);
        std::fill(aspect.begin() + ys[b], aspect.begin() + ys[b + 1] + 1, m);
        std::vector<int> xs;
        for (int i = 0; i < W; i += up.stride * m) xs.push_back(i);
        if (xs.back() != W - 1) xs.push_back(W - 1);
        for (std::size_t a = 0; a + 1 < xs.size(); ++a) {
            blocks.push_back({xs[a], ys[b], xs[a + 1], ys[b + 1]});
            mark(xs[a], ys[b]), mark(xs[a], ys[b + 1]);
        }
        mark(W - 1, ys[b]), mark(W - 1, ys[b + 1]);
    }
    ProgressTracker tracker(progress, n);
    std::size_t marched = 0;
    while (!todo.empty()) {
        std::sort(todo.begin(), todo.end());  // neighbouring rays together, whatever the order found
        marcher.march_rays(&todo, tracker);
        marched += todo.size();
        todo.clear();
        std::vector<Block> split;
        for (const Block& b : blocks) {
            if (b.x1 - b.x0 <= 1 && b.y1 - b.y0 <= 1) continue;  // every pixel it owns is a corner
            const bool finest =
                b.x1 - b.x0 <= up.finest * aspect[std::size_t(b.y0)] && b.y1 - b.y0 <= up.finest;
            if (!lengths_agree(max_distances, b, W)) {
                // A silhouette: split, and at the finest size march every ray it owns.
                if (!finest) {
                    split_block(b, split, mark);
                } else {
                    for (int y = b.y0; y <= b.y1; ++y)
                        for (int x = b.x0; x <= b.x1; ++x) mark(x, y);
                }
                continue;
            }
            if (finest ||
                (corners_agree(result, b, W, up) && !too_wide(result, origins, directions, b, W, up))) {
                grid.blocks.push_back(b);
                continue;
            }
            split_block(b, split, mark);
        }
        blocks = std::move(split);
    }
    interpolate_unmarched(result);
    tracker.advance(n - marched);
    tracker.finish();
}

}  // namespace

// The shared state of CloudLighting (header): its options, and the per-sample light with
// its grids.
struct CloudLighting::Impl {
    Impl(const CloudDensity& d, const CloudIllumination& l, const CloudLightingOptions& o)
        : density(d), light(l), options((o.validate(), o)), sample_light(d, l, options) {}
    const CloudDensity& density;
    const CloudIllumination& light;
    const CloudLightingOptions options;
    const SampleLight sample_light;
};

CloudLighting::CloudLighting(const CloudDensity& density, const CloudIllumination& light,
                             const CloudLightingOptions& options)
    : impl_(std::make_unique<Impl>(density, light, options)) {}
CloudLighting::~CloudLighting() = default;

struct CloudLightingAccess {
    static const CloudLighting::Impl& of(const CloudLighting& lighting) { return *lighting.impl_; }
};

namespace {

// The march of every ray (grid_width == 0), or of a grid of rays (rows of grid_width) with
// upsampling (the header's render_clouds_grid).
CloudResult march(const CloudLighting::Impl& lighting, std::span<const glm::dvec3> origins,
                  std::span<const glm::dvec3> directions, std::span<const double> max_distances,
                  Progress* progress, std::uint64_t first_ray_index, int grid_width,
                  const CloudUpsampling& up) {
    check_rays(origins, directions, max_distances);
    const std::size_t n = directions.size(), nc = lighting.light.channels();
    CloudResult result;
    result.channels = nc;
    result.radiance.assign(n * nc, 0.0f);
    result.transmittance.assign(n, 1.0f);
    result.depth_m.assign(n, 0.0f);
    // Refined, the marched rays are at least `finest` pixels apart (the header's
    // CloudUpsampling): the footprint a marched ray stands for.
    const bool refined = grid_width > 0 && up.stride > 1;
    RayMarcher marcher(lighting.density, lighting.light, lighting.sample_light, origins, directions,
                       max_distances, lighting.options, first_ray_index, result,
                       refined ? double(up.finest) : 1.0);
    if (!refined) {
        ProgressTracker tracker(progress, n);
        marcher.march_rays(nullptr, tracker);
        tracker.finish();
    } else {
        march_refined(marcher, result, origins, directions, max_distances, grid_width, up, progress);
    }
    return result;
}

}  // namespace

CloudResult render_clouds(const CloudDensity& density, const CloudIllumination& light,
                          std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                          std::span<const double> max_distances, const CloudLightingOptions& options,
                          Progress* progress, std::uint64_t first_ray_index) {
    const CloudLighting lighting(density, light, options);
    return march(CloudLightingAccess::of(lighting), origins, directions, max_distances, progress,
                 first_ray_index, 0, {});
}

CloudResult render_clouds_grid(const CloudDensity& density, const CloudIllumination& light,
                               const glm::dvec3& origin, std::span<const glm::dvec3> directions, int width,
                               const CloudLightingOptions& options, const CloudUpsampling& upsampling,
                               Progress* progress, std::uint64_t first_ray_index) {
    for (int a = 0; a < 3; ++a) require_finite(fmt::format("origin[{}]", a), origin[a]);
    return render_clouds_grid(density, light, std::span<const glm::dvec3>(&origin, 1), directions, {}, width,
                              options, upsampling, progress, first_ray_index);
}

CloudResult render_clouds_grid(const CloudDensity& density, const CloudIllumination& light,
                               std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                               std::span<const double> max_distances, int width,
                               const CloudLightingOptions& options, const CloudUpsampling& upsampling,
                               Progress* progress, std::uint64_t first_ray_index) {
    const CloudLighting lighting(density, light, options);
    return render_clouds_grid(lighting, origins, directions, max_distances, width, upsampling, progress,
                              first_ray_index);
}

CloudResult render_clouds_grid(const CloudLighting& lighting, std::span<const glm::dvec3> origins,
                               std::span<const glm::dvec3> directions, std::span<const double> max_distances,
                               int width, const CloudUpsampling& upsampling, Progress* progress,
                               std::uint64_t first_ray_index) {
    upsampling.validate();
    if (width < 1 || directions.size() % std::size_t(width) != 0)
        throw InvalidArgument("width", fmt::format("must divide the number of directions ({}), got {}",
                                                   directions.size(), width));
    CloudUpsampling up = upsampling;
    up.stride = upsampling.resolved_stride(width, int(directions.size() / std::size_t(width)));
    return march(CloudLightingAccess::of(lighting), origins, directions, max_distances, progress,
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

struct CloudViewCache::Impl {
    std::size_t max_bytes;
    std::mutex key_mutex;  // keep(): not during a march (the map's clear is not concurrent)
    std::string key;
    tbb::concurrent_unordered_map<std::uint64_t, Ray> rays;
    std::atomic<std::size_t> bytes{0}, reused{0};
};

CloudViewCache::CloudViewCache(std::size_t max_bytes) : impl_(std::make_unique<Impl>()) {
    impl_->max_bytes = max_bytes;
}

CloudViewCache::~CloudViewCache() = default;

bool CloudViewCache::keep(const std::string& key) {
    std::lock_guard<std::mutex> lock(impl_->key_mutex);
    impl_->reused = 0;
    if (key == impl_->key) return true;
    impl_->rays.clear();
    impl_->bytes = 0;
    impl_->key = key;
    return false;
}

const CloudViewCache::Ray* CloudViewCache::find(std::uint64_t ray) const {
    const auto it = impl_->rays.find(ray);
    if (it == impl_->rays.end()) return nullptr;
    impl_->reused.fetch_add(1, std::memory_order_relaxed);
    return &it->second;
}

void CloudViewCache::store(std::uint64_t ray, Ray&& samples) {
    // A ray's entry: its samples and about the map's node (key, vector, links).
    const std::size_t size = samples.samples.size() * sizeof(Sample) + sizeof(Ray) + 64;
    if (impl_->bytes.fetch_add(size, std::memory_order_relaxed) + size > impl_->max_bytes) {
        impl_->bytes.fetch_sub(size, std::memory_order_relaxed);
        return;
    }
    samples.samples.shrink_to_fit();
    if (!impl_->rays.emplace(ray, std::move(samples)).second)
        impl_->bytes.fetch_sub(size, std::memory_order_relaxed);  // marched twice at once: one kept
}

std::size_t CloudViewCache::rays() const { return impl_->rays.size(); }
std::size_t CloudViewCache::bytes() const { return impl_->bytes.load(); }
std::size_t CloudViewCache::reused() const { return impl_->reused.load(); }

double angle_between_rays(const glm::dvec3& a, const glm::dvec3& b) {
    // 2 asin(|u - v| / 2): accurate for the small angles between neighbouring pixels.
    const double chord = glm::length(glm::normalize(a) - glm::normalize(b));
    return 2.0 * std::asin(std::min(1.0, 0.5 * chord));
}

int CloudUpsampling::resolved_stride(int width, int height) const {
    if (width < 2 || height < 2) return 1;
    if (stride != 0) return stride;
    // A power of two, so that the quadtree halves every block evenly down to `finest`: an
    // odd stride (7) leaves blocks of 3 and 4 pixels whose halves are 1 and 2 wide, and an
    // edge then marches 4 of every 7 columns and rows instead of 1 in 2.
    const double columns = double(width) / kAutoColumns;
    if (columns < 2.0) return 1;
    return std::min(1 << int(std::lround(std::log2(columns))), 16);
}

void CloudUpsampling::validate() const {
    require_in_range("stride", stride, 0, 16);
    require_in_range("finest", finest, 1, 16);
    require_in_range("max_block_size_m", max_block_size_m, 0.0, 1e7, "m");
    require_in_range("transmittance_tolerance", transmittance_tolerance, 0.0, 1.0);
    require_in_range("radiance_tolerance", radiance_tolerance, 0.0, 1.0);
}

}  // namespace welkin
