// SPDX-License-Identifier: Apache-2.0
// Fast cloud lighting: a view-ray march through any cloud density source.
//
// For each view ray from `origin` along d, through the density's majorant segments only
// (empty-space skipping: outside the layer's shell, outside the VDB tree's occupied cells):
//
//  * Steps. The segments' total length L is cut into at most max_steps steps (no shorter
//    than half the density's feature size, so a short path takes fewer); each segment gets
//    a whole number of equal steps. The sample of each step sits at the same fraction u of
//    it, u drawn once per ray from a seeded stream (PathRng(seed, ray)): the jittered start
//    that turns banding into noise, the same on every machine.
//  * The surface. A long path (a layer seen low over the horizon, a heap kilometres away)
//    has steps much longer than the cloud's edge is sharp, and where a cloud's near face
//    falls between two samples is then left to the jitter: its outline and its lobes read
//    as speckled fuzz. So when a base step's sample finds cloud, that step and the one
//    before it (empty at its sample) are cut into n equal pieces, and so is every
//    following step while the cut ones find cloud, and one more past it: n = dt / fine
//    (rounded down, at most surface_cut, 8 by default), fine the longer of half the feature size
//    and the pixel's footprint w(t) (below; a pixel's even where the marched rays stand for
//    more, CloudUpsampling), the finest that a pixel can show. Each piece's
//    sample sits at u of it. The dim tail (next) is not cut. A short path, whose base step
//    is already that fine, is marched as before.
//  * Energy-conserving integration (Hillaire 2015, "Physically based and unified
//    volumetric rendering in Frostbite", SIGGRAPH course, sec. 5.6.3): over a step of
//    length dt with extinction sigma_t and scattering sigma_s = albedo sigma_t, the source
//    S (in-scattered radiance per metre) is integrated analytically against the step's
//    own attenuation,
//        L += T S (1 - exp(-sigma_t dt)) / sigma_t,    T *= exp(-sigma_t dt),
//    so a step never scatters more light than it removes, however long it is.
//  * The dim tail: once T < tail_transmittance (0.1 by default: 90 % of the ray's
//    opacity is behind it) a step spans n = min(8, floor(tail_transmittance / T)) base
//    steps, at the same fraction u: what is left of the ray weighs at most T, so coarser
//    steps there change the result little (docs/validation.md, "Clouds") and save
//    samples. The energy-conserving step keeps the opacity of a long step exact for
//    its sample's sigma_t.
//  * Empty space inside the segments keeps the base step: a longer step there (Schneider
//    2015's adaptive march) passes over wisps thinner than itself
//    (tests/cpp/test_cloud_fast_vs_reference.cpp measures what that costs).
//  * Early termination: once T < min_transmittance the ray stops (what is behind is
//    dimmed below that fraction; T is left as it is, not rounded to 0).
//  * Sun light. At each sample x a shadow ray towards the sun is marched through the
//    density's segments (light_steps midpoint steps, at most light_distance_m) for the
//    cloud's optical depth tau_sun. With shadow_grid (the default) tau_sun is interpolated
//    trilinearly from a lazily filled grid instead (clouds/depth_grid.hpp), aligned with
//    the sun: the vertices on one sun line share one walk, a lookup per cell (light_steps
//    only bounds its step, at most light_distance_m / light_steps, on the coarse levels),
//    and where the rays' footprint is at least half a cell a sample marches the first two
//    cells itself and reads the rest one level coarser ("Near field" there): the finest
//    cell is h_0 =
//    shadow_grid_spacing_m (by default twice the density's feature size), and a sample
//    whose view step is dt reads the level of cell h_0 2^L <= max(dt, h_0), so far
//    samples of a sky, a kilometre apart, share coarse cells. Each vertex march is shared
//    by every sample around it. The level is also no finer than the ray's footprint w(t)
//    (ray_spread_rad, ray_width_m: the distance to the neighbouring rays at the sample;
//    an upsampled grid's marched rays stand for `finest` pixels, CloudUpsampling):
//    a cell narrower than that is read by one ray only, and its vertices cost more than
//    the rays' own samples (a layer kilometres away,
//    a cirrus or altocumulus deck seen from the ground, is where that happens); a pixel
//    cannot show the shadow's detail below its own width (the cone tracing of a pixel's
//    footprint, Amanatides 1984, "Ray tracing with cones", SIGGRAPH). The sun's irradiance
//    E(x) comes through the atmosphere (clouds/illumination.hpp).
//  * Multiple scattering of sun light, by default (multiple_scattering = diffusion) from
//    the delta-Eddington slab along the sun line (clouds/diffusion.hpp, with its
//    derivation): tau_line = tau_sun + tau_antisun, the cloud's optical depth along the
//    sun's line through x (both ways, each at most light_distance_m; a second grid, turned
//    to -s with its first cell marched per sample, on the world's axes under a sun below
//    15 degrees, whose turned lines run nearly along a deck's base and streak it; read at
//    the sun's level; every grid interpolates the mean extinction along its lines, the
//    depth's kink at a layer's faces exact, depth_grid.hpp "Chord"), and with nu = d . s,
//        S_sun = sigma_s E(x) [exp(-tau_sun) p(nu) + (exp(-tau'_sun) - exp(-tau_sun)) p2(nu)
//                              + <phi + 3 g F mu0 nu> / (4 pi E)],
//    single scattering (exact), the light scattered into the forward peak (similarity
//    scaling tau' = (1 - albedo g) tau, the twice-scattered phase p2), and Eddington's
//    diffuse field of the scaled slab, averaged over the slab's unknown inclination: the
//    diffuse light falls off linearly with depth, as diffusion theory has it, where the
//    octaves below vanish. With `sides` (the default) the slab is finite across the sun
//    line: the cloud's chord tau_side along the horizontal normal to the sun (a third
//    grid, read both ways along its lines, two levels coarser across the ground and a
//    quarter of the sun's cell in the vertical) makes the diffuse light
//    leak through its sides (clouds/diffusion.hpp, "The sides"). No fitted parameter. Its error against
//    the reference (bench/clouds, bench/clouds/lighting_vs_reference.py) and against Cycles
//    (bench/cycles_clouds.py) is in docs/validation.md ("Clouds"). octaves = 1 is single
//    scattering in either mode.
//  * The octaves (multiple_scattering = octaves): Wrenninge et al. 2013 ("Oz: the great
//    and volumetric", SIGGRAPH talk; also Wrenninge 2015, "Art-directable multiple
//    volumetric scattering", SIGGRAPH talk): with a, b, c in (0, 1],
//        S_sun = sigma_s E(x) sum_{i<octaves} b^i exp(-a^i tau_sun) p(nu; c^i g),
//    each octave standing for light that has scattered more often: it is less attenuated
//    (a), weaker (b) and less peaked (c). a <= b keeps each octave below the
//    single-scattering energy (Wrenninge's condition).
//    The octaves' fixed shares b^i assume a cloud large enough for light to scatter many
//    times; in an optically small cloud it leaves after the first event. With
//    octave_optical_size (the default) octave i is weighted by f^i, f = 1 - exp(-tau_line):
//    f is the probability that
//    light travelling along that line interacts once more before it leaves the cloud, so
//    the i-times-further-scattered share goes as f^i, as the successive orders of
//    scattering do in an optically thin medium (order n+1 / order n ~ tau, e.g. Hansen &
//    Travis 1974, "Light scattering in planetary atmospheres", sec. 3) and tends to
//    Wrenninge's b^i in a thick one (docs/validation.md, "Clouds").
//  * Sky light. The sky is a radiance L_a(x) from above the local horizon and L_b(x) from
//    below it (clouds/illumination.hpp). In a uniform isotropic field (L_a = L_b = L) a
//    conservative medium (albedo 1) changes nothing: the radiance is L everywhere inside,
//    at all orders of scattering (in-scattering sigma_s L equals extinction sigma_t L), so
//    the source is exactly S_sky = sigma_s L, however deep the point. With two skies the
//    field inside is a mix that depends on the depths to the cloud's top and base. Take
//    the cloud at x as a plane-parallel conservative slab, its scaled optical depths
//    tau'_up and tau'_down (tau' = (1 - albedo g) tau, the transport depth) towards the
//    zenith and the nadir, D = tau'_up + tau'_down + 4/3. In Eddington's approximation the
//    radiance is I0 + I1 mu (mu the cosine of the light's direction with the nadir); I0 = J
//    is linear in depth, I1 = -dJ/dtau' is constant, and Marshak's conditions, J -+ (2/3)
//    I1 = L_a at the top and L_b at the base (isotropic radiance falling on each face),
//    give
//        J = L_a (tau'_down + 2/3) / D + L_b (tau'_up + 2/3) / D,   I1 = (L_a - L_b) / D
//    (e.g. Thomas & Stamnes 1999, "Radiative Transfer in the Atmosphere and Ocean", ch. 7;
//    Bohren & Clothiaux 2006, "Fundamentals of Atmospheric Radiation", ch. 5-6). The
//    phase turns the dipole I1 mu into g I1 mu' (Funk-Hecke, chi_1 = g), mu' = d . z for a
//    view ray d: light sent down to a viewer below carries the net downward flux. So
//        w_a = (tau'_down + 2/3) / D + g (d . z) / D,  w_b = (tau'_up + 2/3) / D - g (d . z) / D,
//    each clamped at 0 (Eddington's radiance goes negative for g > 2/3 at a face's
//    grazing views; never below 0 here). The mix is exact for L_a = L_b, gives the mean
//    (w = 1/2) in a thin cloud seen edge-on, and at the base of a thick slab the light let
//    through plus L_b (tests/cpp/test_cloud_lighting.cpp, TwoSkies..., against the
//    reference); ambient_steps = 0 takes the mean throughout.
//    With absorption the field decays into the cloud; diffusion theory gives the asymptotic
//    decay exp(-kappa tau) with kappa = sqrt(3 (1 - albedo) (1 - albedo g)) per unit
//    optical depth (the inverse diffusion length, sigma_a and the transport coefficient
//    sigma_t (1 - albedo g); Bohren & Clothiaux, ch. 6), g the phase's mean cosine, each
//    sky's light decaying from its own face. The march takes tau_up and tau_down from one
//    ray each towards the local zenith and nadir (ambient_steps steps; with shadow_grid, on
//    grids aligned with the zenith at the world's origin, read one level coarser than the
//    sun's; neither for a uniform sky of albedo 1):
//        S_sky = sigma_s (w_a L_a exp(-kappa tau_up) + w_b L_b exp(-kappa tau_down)).
//    Exact for a uniform sky and albedo 1 (tests/cpp/test_cloud_lighting.cpp,
//    UniformSky...), an estimate otherwise (the true depths are over all directions, not
//    the vertical alone; the cloud is not a slab).
//
// Outputs per ray (premultiplied, "over" the background): the in-scattered radiance per
// channel (W m^-2 sr^-1 nm^-1, the illumination's channels), the transmittance T (grey:
// cloud extinction does not depend on wavelength), and the depth: the distance from the
// origin to the transmittance-weighted centre of the scattering, sum t dA / sum dA with
// dA = T (1 - exp(-sigma_t dt)) the opacity each step adds; 0 where nothing was hit.
// A background radiance B composites as L + T B.
//
// Results do not depend on the thread count (each ray is independent and seeded).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/base/progress.hpp"
#include "welkin/clouds/density.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/phase.hpp"

namespace welkin {

struct CloudScattering {
    double albedo = 1.0;  // single-scattering albedo of cloud droplets, [0, 1]
    CloudPhase phase;
    void validate() const;
};

// The view samples of marched rays, kept so that the same rays through the same clouds can
// be lit again without marching them. Where a ray's samples fall, and each one's step and
// extinction, depend on the density, the ray and the march's options alone; the light
// enters only each sample's source. So a march that finds its ray here (keyed by the ray's
// index, first_ray_index + r of render_clouds / render_clouds_grid) lights the stored
// samples, and one that does not marches the ray and stores them. The radiance, the
// transmittance and the depth are the march's, bit for bit: the same samples in the same
// order, lit by the same light and depth grids. What it saves is the march through the
// clouds' empty parts, most of a thin layer's time, and each sample's depths towards the
// zenith and the nadir: the sky's weights in its source depend on them, on the view ray and
// on whether the sky is two skies or one, not on the sun, so a sample keeps them (with the
// ray's kind of sky: another kind lights it afresh). The light's depths along the sun are
// walked as before (docs/validation.md, "Lighting the same rays again").
// The caller vouches that nothing but the light changed (the sun, the sky, the atmosphere
// that makes them): keep(key) empties the cache unless the key, the caller's fingerprint of
// the clouds, the rays and the options, is the one it holds. Marches may find and store at
// once; keep() runs between marches. Rays past max_bytes are not stored (they are marched
// every time).
class CloudViewCache {
public:
    struct Sample {
        double t, h, sigma_t;  // the sample's distance along the ray, its step, its extinction
        double above, below;   // the sky's weights in its source (they do not depend on the sun)
    };
    struct Ray {
        double dt_target = 0.0;  // the ray's base step (RayLevels' view step)
        bool two_skies = true;   // whether above and below are the two skies' (a sky of one: not)
        std::vector<Sample> samples;
    };
    explicit CloudViewCache(std::size_t max_bytes = std::size_t(256) << 20);
    ~CloudViewCache();
    CloudViewCache(const CloudViewCache&) = delete;
    CloudViewCache& operator=(const CloudViewCache&) = delete;

    // Keeps the stored rays if `key` is the one they were stored under; else empties the
    // cache for it. Returns whether they were kept.
    bool keep(const std::string& key);
    const Ray* find(std::uint64_t ray) const;  // nullptr: not stored
    void store(std::uint64_t ray, Ray&& samples);
    std::size_t rays() const;    // stored
    std::size_t bytes() const;   // their samples' memory
    std::size_t reused() const;  // rays found since the last keep()

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// How the march approximates the orders of sun light beyond the first (see above).
enum class CloudMultipleScattering {
    octaves,    // Wrenninge's octaves (weighted by the optical size when octave_optical_size)
    diffusion,  // the delta-Eddington slab along the sun line (clouds/diffusion.hpp)
};

struct CloudLightingOptions {
    CloudScattering scattering;
    int max_steps = 96;                // along each view ray, [1, 4096]
    int surface_cut = 8;               // the most pieces a step is cut into at a surface, [1, 64]; 1: off
    int light_steps = 8;               // along each shadow ray, [1, 256]
    int ambient_steps = 4;             // along the rays to the zenith and nadir, [0, 256] (0: see above)
    double light_distance_m = 4000.0;  // how far the shadow and sky rays look, (0, 1e6]
    CloudMultipleScattering multiple_scattering =
        CloudMultipleScattering::diffusion;  // orders >= 2 (see above)
    int octaves = 4;                   // Wrenninge's octaves, [1, 16]; 1: single scattering in either mode
    double octave_extinction = 0.5;    // a, (0, 1]
    double octave_contribution = 0.5;  // b, (0, 1]
    double octave_eccentricity = 0.5;  // c, (0, 1]
    bool octave_optical_size = true;   // scale octave i by (1 - exp(-tau_line))^i (see above)
    bool sides = true;  // diffusion: light leaks through the cloud's sides across the sun line (above)
    double min_transmittance = 1e-3;  // early termination, [0, 1)
    double tail_transmittance = 0.1;  // below it, longer view steps (see above), [0, 1]; 0: off
    std::uint64_t seed = 1;
    bool jitter = true;           // false: samples at step midpoints
    double max_distance_m = 1e6;  // view rays end here, (0, 1e8]
    // Tabulate the optical depths towards the sun (and the zenith) on a lazily filled grid
    // (clouds/depth_grid.hpp) instead of marching a shadow ray per sample.
    bool shadow_grid = true;
    double shadow_grid_spacing_m = 0.0;  // finest cell h_0, [0, 1e5] m; 0: twice the feature size
    // The footprint of a view ray at distance t, w(t) = ray_width_m + ray_spread_rad t: the
    // distance between neighbouring rays of the image (a pixel), which its host knows (the
    // angle between neighbouring rays of a perspective or panoramic image, the width of an
    // orthographic camera's pixel). The optical-depth grids are read no finer than it (see
    // the header, "Sun light"). Both 0: unknown (the levels by the view step alone). The
    // hosts set it: the sky image (sky_image.hpp) and the camera passes (cloud_passes.hpp)
    // from the angle (angle_between_rays) and distance between two neighbouring pixels' rays.
    // An upsampled grid (render_clouds_grid, stride > 1) marches its rays with it `finest`
    // times as wide (CloudUpsampling).
    double ray_spread_rad = 0.0;  // [0, 1]
    double ray_width_m = 0.0;     // [0, 1e6] m
    // The marched rays' samples, read and stored by the march (above); null: none kept.
    std::shared_ptr<CloudViewCache> view_cache;

    void validate() const;
};

// The angle between two directions (radians; any length but zero), accurate for the small
// angles between neighbouring pixels: a host's ray_spread_rad.
double angle_between_rays(const glm::dvec3& a, const glm::dvec3& b);

// Which rays of a grid (render_clouds_grid) were marched, and how each other ray was
// interpolated: bilinearly from the four corner rays of the block that owns it. A block
// [x0, x1] x [y0, y1] owns the pixels of [x0, x1) x [y0, y1), its right edge included
// when x1 is the last column and its bottom edge when y1 is the last row; every pixel is
// owned by one block. Hosts interpolate their own per-ray quantities (the air in front
// of a cloud, a composite) the same way, so that they need them for the marched rays only.
struct CloudGridInterpolation {
    struct Block {
        int x0, y0, x1, y1;  // corner columns and rows, x0 < x1 or y0 < y1
        // The corner pixels in a grid `width` wide: top-left, top-right, bottom-left,
        // bottom-right.
        std::array<std::size_t, 4> corners(int width) const {
            const std::size_t w = std::size_t(width);
            return {y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1};
        }
    };
    int width = 0, height = 0;
    std::vector<Block> blocks;           // the blocks whose unmarched pixels are interpolated
    std::vector<unsigned char> marched;  // per ray (row-major); empty: every ray was marched

    bool all_marched() const { return marched.empty(); }
    // Whether ray p was marched (not interpolated).
    bool was_marched(std::size_t p) const { return marched.empty() || marched[p] != 0; }
    // f(p, q, w) for every unmarched pixel p, q its block's corner pixels (top-left,
    // top-right, bottom-left, bottom-right) and w their bilinear weights; in parallel,
    // each pixel once.
    template <class F>
    void for_each_interpolated(F&& f) const;
    // values: (width x height, channels); the unmarched pixels' values set from their
    // corners.
    void interpolate(std::span<float> values, std::size_t channels) const;
};

// (N, C) radiance, N transmittances and depths; standard errors from estimators only.
struct CloudResult {
    std::size_t channels = 0;
    std::vector<float> radiance;             // (N, C)
    std::vector<float> transmittance;        // N
    std::vector<float> depth_m;              // N
    std::vector<float> radiance_error;       // (N, C) standard error, or empty
    std::vector<float> transmittance_error;  // N, or empty
    CloudGridInterpolation interpolation;    // render_clouds_grid: which rays were marched
};

// The lighting of one density under one light with one set of options, shared by the
// marches of one frame's parts (the render engine's bands of rows): the per-sample light
// and its shadow grids, filled lazily by every march that uses it, so that the vertices
// the bands share are walked once. A vertex's depth does not depend on which march filled
// it, so the results are those of one march over the whole frame. Keeps references to the
// density and the light (they must outlive it) and a copy of the options (validated:
// InvalidArgument). Safe for several marches at once. Its memory is the grids' tiles, as
// one march over the frame would fill them.
class CloudLighting {
public:
    CloudLighting(const CloudDensity& density, const CloudIllumination& light,
                  const CloudLightingOptions& options);
    ~CloudLighting();
    CloudLighting(const CloudLighting&) = delete;
    CloudLighting& operator=(const CloudLighting&) = delete;

    struct Impl;

private:
    friend struct CloudLightingAccess;  // lighting.cpp's march
    std::unique_ptr<Impl> impl_;
};

// Throws InvalidArgument for bad options, a non-finite origin or a bad direction (naming
// view_directions[i]); Cancelled when `progress` cancels.
CloudResult render_clouds(const CloudDensity& density, const CloudIllumination& light,
                          const glm::dvec3& origin, std::span<const glm::dvec3> directions,
                          const CloudLightingOptions& options = {}, Progress* progress = nullptr);

// The same for rays with their own origins and lengths (camera passes: orthographic rays
// start on the camera's plane, and rays end at the scene's geometry): ray i starts at
// origins[i] (origins[0] for all when there is one) and ends at min(max_distances[i],
// options.max_distance_m) (at options.max_distance_m when max_distances is empty). Ray i
// is seeded by first_ray_index + i (a band of a frame seeded as in the whole frame).
// InvalidArgument names origins[i] or max_distances[i] (negative or NaN) or a size mismatch.
CloudResult render_clouds(const CloudDensity& density, const CloudIllumination& light,
                          std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                          std::span<const double> max_distances, const CloudLightingOptions& options = {},
                          Progress* progress = nullptr, std::uint64_t first_ray_index = 0);

// Upsampling of a grid of rays (render_clouds_grid): a cloud sky is mostly smooth (clear
// sky, cloud interiors) with sharp edges between. The rays at every stride-th row and
// every (stride x aspect)-th column (and the last ones) are marched first. The aspect, per
// lattice row, makes the blocks about square in angle: the angle between neighbouring
// rows over that between neighbouring columns, rounded down to a power of two (at most
// 32); 1 for a pinhole camera, 1 / cos(elevation) for an equirect's rows, whose columns
// crowd towards the poles. Then, as a quadtree, each block whose four marched corner rays
// disagree (transmittances more than transmittance_tolerance apart, or a channel's
// radiances more than radiance_tolerance of the largest) is split in four at its
// midpoints, whose rays are marched, down to blocks `finest` pixels tall (finest x aspect
// wide); the rays inside the blocks left are interpolated bilinearly from their corners
// (CloudGridInterpolation). Refining only the blocks that straddle an edge marches about
// the edge's length in pixels per level, instead of every pixel of every block it
// touches; finest 2 leaves the last level (half the rays an edge costs) interpolated, an
// edge softened over two pixels. The marched rays are then at least `finest` pixels apart,
// and each is marched with a footprint that wide (ray_spread_rad and ray_width_m times
// finest): its optical-depth grids are read at the marched rays' spacing, whose vertices
// the neighbouring marched rays share, and not a pixel's, which no other marched ray would
// read (docs/validation.md, "The marched rays' footprint"). A silhouette's rays, all
// marched at the finest size (below), are marched so too. A block is also split, however
// well its corners agree, while it spans more than max_block_size_m at the farthest cloud
// its corners see (the angle between its corner rays times that depth): near a horizon
// the clouds are tens of
// kilometres away and their shapes smaller than a block, whose corners can agree by
// chance. Deterministic: a ray's value is its own march or a fixed combination of marched
// rays, whatever the thread count.
// Rays that end at the scene's geometry (a camera's rays with lengths) are interpolated
// only between rays of the same kind: a block is interpolated when every ray in it is
// unbounded (the sky), or every one ends within kLengthTolerance of the others (one smooth
// surface). A block with a silhouette in it is split, and at the finest size its rays are
// all marched, so a cloud never bleeds over the geometry in front of it. Rays that end at
// nearby geometry cost little: the march stops at their end.
// What is lost: a cloud smaller than a block between four corner rays that agree (four
// clear rays around a small wisp) is interpolated away. docs/validation.md ("Speed of a
// cloudy sky", "Every type's sky and plate") charts time against error for these
// settings, against marching every ray.
struct CloudUpsampling {
    static constexpr int kAutoColumns = 256;          // stride 0: about the grid's width / this
    static constexpr double kLengthTolerance = 0.01;  // relative, between bounded rays
    // Coarse lattice, [0, 16]: 0 (the default) about one marched column per 1/256 of the
    // width, the power of two nearest (every 1.4 degrees of an equirect sky: stride 8 at
    // 2048 wide, and at 1920), 1 every ray marched.
    int stride = 0;
    int finest = 2;                        // [1, 16]: blocks this wide are not split
    double transmittance_tolerance = 0.1;  // [0, 1]
    double radiance_tolerance = 0.3;       // [0, 1], relative
    double max_block_size_m = 500.0;       // [0, 1e7] m
    void validate() const;
    // The lattice's stride for a grid width x height: `stride`, or with 0 the power of two
    // nearest width / kAutoColumns (in ratio: 7.5 -> 8, 5 -> 4), 1 where that is below 2, at
    // most 16; 1 for a single row or column.
    int resolved_stride(int width, int height) const;
};

// render_clouds for the rays of an image (rows of `width` rays, row-major, from `origin`),
// upsampled as CloudUpsampling says. Ray i is seeded by first_ray_index + i.
CloudResult render_clouds_grid(const CloudDensity& density, const CloudIllumination& light,
                               const glm::dvec3& origin, std::span<const glm::dvec3> directions, int width,
                               const CloudLightingOptions& options = {},
                               const CloudUpsampling& upsampling = {}, Progress* progress = nullptr,
                               std::uint64_t first_ray_index = 0);

// The same for rays with their own origins and lengths (render_clouds' second form): a
// camera's frame, or a band of its rows. The lattice's rows are the grid's rows 0, stride,
// 2 stride, ... and its last: a band cut at lattice rows, marched with the frame's
// resolved stride, has exactly the frame's values (render_cloud_passes does so).
CloudResult render_clouds_grid(const CloudDensity& density, const CloudIllumination& light,
                               std::span<const glm::dvec3> origins, std::span<const glm::dvec3> directions,
                               std::span<const double> max_distances, int width,
                               const CloudLightingOptions& options = {},
                               const CloudUpsampling& upsampling = {}, Progress* progress = nullptr,
                               std::uint64_t first_ray_index = 0);

// The same with a frame's shared lighting (CloudLighting): what the bands of one frame use.
CloudResult render_clouds_grid(const CloudLighting& lighting, std::span<const glm::dvec3> origins,
                               std::span<const glm::dvec3> directions, std::span<const double> max_distances,
                               int width, const CloudUpsampling& upsampling = {},
                               Progress* progress = nullptr, std::uint64_t first_ray_index = 0);

template <class F>
void CloudGridInterpolation::for_each_interpolated(F&& f) const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 64), [&](const auto& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            const Block& b = blocks[k];
            const std::size_t w = std::size_t(width);
            const std::array<std::size_t, 4> corners = b.corners(width);
            const std::size_t* q = corners.data();
            const int x_end = b.x1 == width - 1 ? b.x1 + 1 : b.x1,
                      y_end = b.y1 == height - 1 ? b.y1 + 1 : b.y1;
            for (int y = b.y0; y < y_end; ++y) {
                const double v = b.y1 > b.y0 ? double(y - b.y0) / double(b.y1 - b.y0) : 0.0;
                for (int x = b.x0; x < x_end; ++x) {
                    const std::size_t p = std::size_t(y) * w + std::size_t(x);
                    if (marched[p]) continue;
                    const double u = b.x1 > b.x0 ? double(x - b.x0) / double(b.x1 - b.x0) : 0.0;
                    const double weights[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};
                    f(p, q, weights);
                }
            }
        }
    });
}

}  // namespace welkin
