// SPDX-License-Identifier: Apache-2.0
// A procedural cloud layer on the curved planet, after Schneider's Nubis clouds
// (Schneider & Vos 2015, "The real-time volumetric cloudscapes of Horizon Zero Dawn",
// SIGGRAPH Advances in Real-Time Rendering; Schneider 2017, "Nubis: authoring real-time
// volumetric cloudscapes with the Decima engine"; GPU Pro 7, ch. 4 "Real-time volumetric
// cloudscapes").
//
// The layer is the spherical shell between bottom_altitude_m and top_altitude_m above a
// ground of radius planet_radius_m, whose centre is straight below the world origin
// (which stands origin_altitude_m above the ground, docs/design.md). A layer has one cloud
// type (CloudType), whose preset (CloudLayerParams::preset) gives altitudes, scales and
// density typical of it, and whose shape constants (below) give its height profile.
// At a point p with altitude h and height fraction f = (h - bottom) / (top - bottom):
//   weather map (2D, a texture of period weather_scale_m read hex-tiled, below), w the weather
//       texture (Perlin fBm):
//       local coverage c = clamp(k (1 + weather_variation (2 w_r - 1)), 0, 1), k the
//       internal coverage (below); the local top fraction f_max = 1 - towers (1 - w_g)
//       (cumulus: tall towers where w_g is high, low mounds elsewhere);
//   no tiling: the weather map and the base shape are read hex-tiled (noise.hpp, hex_taps: each
//       vertex of a triangular lattice half a period apart reads the texture at an offset of its
//       own, blended keeping the contrast), so neither repeats at its period: read as they are,
//       over tens of periods from above and towards the horizon, the periods show as a diagonal
//       ribbing (docs/validation.md, "Tiling"; tests/python/test_cloud_tiling.py);
//   base = remap(pw, -(1 - fbm_w), 1, 0, 1), pw the base texture's Perlin-Worley channel and fbm_w
//       its Worley octaves (tile base_scale_m, stretched by the type's `stretch` along a direction
//       30 degrees off the x axis, read at a point displaced by a domain warp from the weather
//       map's b, a channels); every type then builds its clouds its own way (the WMO
//       International Cloud Atlas's descriptions, docs/artists.md#cloud-types):
//  * cells (cumulus, stratocumulus, altocumulus: a flat base, a heap, lobes):
//       the footprint m = clamp(remap(base, 1 - c, 1, 0, 1)) from the base texture read at
//       one height (h = evolution_m: every cell keeps its outline up the layer; baked once
//       into a 2D slice), and m_peak, the footprint at the top of the cell the point lies
//       in, from the peak map (the base slice split into the basins of its maxima by
//       steepest ascent, each texel holding its basin's highest value; procedural.cpp,
//       bake_slice), the slice's third channel, read with the same taps; over
//       the footprint a dome f_top = H u^0.6, u = m / m_peak (1 - r^2 / rho^2 about a cell's
//       top, r the distance from it: level at every cell's top, steeper at the foot than a
//       paraboloid, narrower upwards: the atlas's mounds and domes), rho = m_peak 0.12
//       base_scale_m its radius (about a Worley cell's radius at m = 1), its height H = f_max
//       v (2 - v), v = min(1, rho dome / (f_max thickness)), `dome` the small cells' height
//       over their width, a wider cell taller, flattening at the local top f_max (humilis);
//       the point is inside = min((f_top - f) thickness cos(slope), rho - r) metres in (along
//       the surface's normal), less the lobes' bite: the detail texture's three Worley
//       octaves W_o read at half its frequency (cells detail_scale_m / 2, / 4, / 8), bite =
//       2 detail_strength billow (detail_scale_m / 2) L sum_o a_o (1 - W_o), a = (1, 0.3,
//       0.09), each a paraboloid around its feature points (rounded bulges on bulges,
//       creased between them: cauliflower), the lookup bent by the curl noise and shifted by
//       the weather map's warp, L = clamp(f / base_erosion) (0.3 + 0.7 f / f_max) (none at
//       the base, most at the top); density = clamp(f / a1) clamp((inside - bite) / kEdgeM),
//       a1 the type's gradient's first corner (the base's rise over a few tens of metres);
//  * the layer (stratus): height gradient G(f / f_max), the type's trapezoid (0 below a0,
//       up to 1 at a1, 1 to a2, down to 0 at a3), the base texture read at the height
//       h - bottom + evolution_m; covered = clamp(remap(base G, 1 - c, 1, 0, 1))
//       (Schneider's remap by coverage); erosion (3D, tile detail_scale_m, read at the same
//       height, its lookup displaced by the curl noise, Nubis's "curl distortion", stronger
//       at the bottom): the detail Worley fBm, inverted towards the top and faded out at the
//       base by `base_erosion`; at most kMaxErosion of the range is eroded, and only where
//       the cloud is thin, so that raising the detail shapes edges and leaves no isolated
//       specks: density = clamp(remap(covered, e, 1, 0, 1)), e = kMaxErosion detail_strength
//       (1 - covered) modifier;
//  * cirrus (heads with hooked fallstreaks of fibres, the atlas's uncinus): c further thinned
//       into patches a few kilometres wide with clear sky between (the weather map read at 4
//       times its frequency, its r channel wp: c = clamp(c_raw clamp(2.5 wp - 0.75))); a
//       point s = clamp((a1 - f) / a1) of the way down from the heads lies under the head
//       point xb = x - D(s), D = thickness (shear s e_along + hook s^2 e_across) (the ice
//       falling from a head drifts in a wind whose shear turns with height: the trail leaves
//       the head along the streaks and bends across them, a hook; hook varies over the
//       weather's scale), the lookup also bent by the curl noise; the footprint m at xb as
//       for cells; the head the type's trapezoid G(f) near the top, the fallstreak below it
//       down to s = fall m, thinning downwards; density = max(head, tail) clamp(m / 0.2)
//       (1 - min(1, fibres detail_strength) (1 - strands)), strands = clamp(remap(fbm_d,
//       0.45, 0.75, 0, 1)) of the detail texture read at xb (a grain of the head, 0.25 and
//       0.6 times the detail frequency along and across the streaks, carried down its fall
//       curve: each grain draws a strand, many to a trail);
//   sigma_t = density_per_m * density.
// Every factor is in [0, 1], so density <= 1: the majorant is density_per_m on the shell.
// Clear air by construction is skipped before any texture read (sigma_t returns the same
// value, sooner): a cell's top is below f_max v (2 - v) at m = 1, so above that ceiling (at
// f_max = 1 for the layer, at the point's own f_max once the weather map is read) the
// density is 0; cirrus has none below min(a0, a1 (1 - fall)) (the head's foot, the longest
// fallstreak's); the layer model none outside [a0 (1 - towers), a3]. Deep inside a cell,
// more than the deepest lobe (1.39 times the lobes' scale) plus kEdgeM in, the density is
// clamp(f / a1) whatever the detail noise reads, and it is not read.
//
// Coverage means coverage, in one of two measures (coverage_measure):
//  * dome (the default): the share of the sky dome a ground observer sees covered, the WMO's
//    cloud amount (oktas / 8; WMO International Cloud Atlas, "Cloud amount", and the Guide to
//    Instruments and Methods of Observation, WMO-No. 8, vol. I, ch. 15): the solid-angle
//    weighted share of the directions more than kDomeMinElevationDeg above the horizon
//    whose slant optical depth through the layer reaches kCoverageOpticalDepth. Seen from
//    the ground a layer looks more covered than its area share, the clouds' sides filling
//    the gaps at slant angles (docs/validation.md, "Coverage and cloud types");
//  * area: the share of the ground's area over which the layer's vertical column is
//    cloudy, a column being cloudy when its vertical optical depth is at least
//    kCoverageOpticalDepth (about a quarter of the light stopped).
// The internal coverage k above is found at construction by bisection so that the
// measured share equals `coverage` (the share grows with k: the density grows with k at
// every point, so the bisection converges): for the area, over kCoverageColumns columns on
// a deterministic low-discrepancy set of points (a square of two weather tiles,
// covered_fraction); for the dome, over kDomeDirections directions (equal solid angles)
// from each of kDomeObservers ground points on the same kind of set (dome_fraction).
// Both sets lie in the field's own frame, so k does not depend on the wind. Coverage 0 is
// a clear sky and 1 an overcast one.
//
// The shape constants are Welkin's choice, in the spirit of Schneider's hand-drawn height
// gradients (GPU Pro 7, fig. 4.7) and of the WMO International Cloud Atlas's descriptions
// of each genus: they are parameters of look, not physics.
//
// Deterministic: the noise is baked from the seed by integer hashing (noise.hpp), and the
// calibration's columns are fixed points: the same on every machine.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include <glm/vec2.hpp>

#include "welkin/clouds/density.hpp"
#include "welkin/clouds/noise.hpp"

namespace welkin {

enum class CloudType { cumulus, stratocumulus, altocumulus, stratus, cirrus };

// What `coverage` measures (the header): the share of the ground's area under cloud, or of
// the sky dome a ground observer sees covered (oktas / 8).
enum class CloudCoverageMeasure { area, dome };
constexpr std::array<std::string_view, 2> kCoverageMeasureNames{"area", "dome"};
std::string_view coverage_measure_name(CloudCoverageMeasure measure);
// InvalidArgument naming `parameter` and listing the accepted names for an unknown one.
CloudCoverageMeasure coverage_measure_from_name(std::string_view name,
                                                const std::string& parameter = "coverage_measure");

// "cumulus", "stratocumulus", "altocumulus", "stratus", "cirrus".
constexpr std::array<std::string_view, 5> kCloudTypeNames{"cumulus", "stratocumulus", "altocumulus",
                                                          "stratus", "cirrus"};
std::string_view cloud_type_name(CloudType type);
// InvalidArgument naming `parameter` and listing the accepted names for an unknown one.
CloudType cloud_type_from_name(std::string_view name, const std::string& parameter = "cloud_type");

struct CloudLayerParams {
    CloudType cloud_type = CloudType::cumulus;
    double bottom_altitude_m = 1200.0;  // [0, 20000), below top
    double top_altitude_m = 3200.0;     // (bottom, 20000]
    double coverage = 0.4;              // [0, 1]: share of the area or the dome under cloud (header)
    CloudCoverageMeasure coverage_measure = CloudCoverageMeasure::dome;  // what coverage measures
    double density_per_m = 0.04;         // sigma_t of the densest cloud, m^-1, [0, 10]
    double base_scale_m = 5000.0;        // tile of the base shape, [10, 1e6] m (cumulus: 8000)
    double detail_scale_m = 700.0;       // tile of the erosion noise, [1, 1e6] m
    double weather_scale_m = 30000.0;    // tile of the weather map, [10, 1e7] m
    double detail_strength = 0.5;        // [0, 1]
    double weather_variation = 0.6;      // [0, 1]
    glm::dvec2 wind_offset_m{0.0, 0.0};  // shifts the field by this much, each in [-1e9, 1e9] m
    // Moves the base and detail noise through the layer's height by this much (finite, m),
    // the heights of the layer and of its type's gradient staying put: keyed over time the
    // shapes change in place (Schneider's evolving noise) while wind_offset_m carries them;
    // one base_scale_m brings the base shape back.
    double evolution_m = 0.0;
    std::uint64_t seed = 1;
    double planet_radius_m = 6360e3;  // [1e3, 1e8]
    double origin_altitude_m = 0.0;   // of the world origin above the ground, [0, 1e6]

    // The preset of a cloud type (the defaults above are cumulus's, but for its 8 km base tile).
    static CloudLayerParams preset(CloudType type);
    void validate() const;  // InvalidArgument naming the field and its range
};

class ProceduralClouds final : public CloudDensity {
    friend struct ProceduralCloudsTestAccess;  // tests/cpp/test_cloud_density.cpp

public:
    // A column is cloudy when its vertical optical depth reaches this (opacity 26 %).
    static constexpr double kCoverageOpticalDepth = 0.3;
    static constexpr int kCoverageColumns = 2048;
    static constexpr double kMaxErosion = 0.6;
    static constexpr double kEdgeM = 60.0;  // cells: the density's rise inside the surface
    static constexpr double kDomeMinElevationDeg = 5.0;
    static constexpr int kDomeObservers = 32;
    static constexpr int kDomeDirections = 64;

    explicit ProceduralClouds(const CloudLayerParams& params);

    double sigma_t(const glm::dvec3& p) const override;
    void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const override;
    double feature_size_m() const override;

    const CloudLayerParams& params() const { return p_; }
    // The share of `columns` columns (the header's point set) whose vertical optical depth
    // reaches kCoverageOpticalDepth: the measured coverage.
    double covered_fraction(int columns = kCoverageColumns) const;
    // The share of the dome covered (the header), averaged over `observers` ground points,
    // each seeing `directions` directions of equal solid angle: the measured dome coverage.
    double dome_fraction(int observers = kDomeObservers, int directions = kDomeDirections) const;

    // The type's height gradient G(f) for f in [0, 1] of its local height (0 outside).
    static double height_gradient(CloudType type, double f);

private:
    // `skip`: return early where the shape is clear air by construction (the header's last
    // paragraph on the formulas); false evaluates the whole shape (the same value, which
    // tests/cpp/test_cloud_density.cpp checks).
    double density(const glm::dvec3& p, double h, double k, bool skip = true) const;
    double footprint(double u, double v, double c, double* m_peak = nullptr) const;
    double cell_density(double x, double y, double f, double c, const float* w, bool skip) const;
    // The highest height fraction a cell can reach under local top f_max (its dome at m = 1).
    double cell_ceiling(double f_max) const;
    double heap_v(double rho, double f_max) const;
    double cirrus_density(double x, double y, double f, double c, const float* w) const;
    double column_depth(double x, double y, double k) const;
    double fraction(double k, int columns) const;
    double dome_share(double k, int observers, int directions) const;
    double slant_depth(const CloudRay& ray, double k, std::vector<MajorantSegment>& segs) const;
    void shell(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const;

    CloudLayerParams p_;
    double k_ = 0.0;
    // The height fractions outside which the type's shape is clear air (open interval).
    double band_lo_ = 0.0, band_hi_ = 1.0;
    glm::dvec3 centre_;
    std::shared_ptr<const CloudNoiseTextures> noise_;
    // The channels sigma_t reads, combined once: base (pw, fbm_w), detail (fbm_d and its
    // three Worley octaves), weather
    // (r, g, b, a), curl (x, y).
    PeriodicTexture<2> base_, curl_;
    PeriodicTexture<4> weather_;
    PeriodicTexture<4> detail_;
    // The footprints' slice: the base texture at h = evolution_m (its two channels) and, for
    // the cell types, the peak map (per texel, the highest base value of its basin; header).
    PeriodicTexture<3> slice_;
    double inv_weather_ = 0.0, inv_base_ = 0.0, inv_detail_ = 0.0;  // 1 / the tile scales
    double thickness_ = 0.0;                                        // top - bottom altitude, m
    double inv_thickness_ = 0.0;                                    // 1 / thickness_
    double sqrt_stretch_ = 1.0;                                     // the square root of the type's stretch
    // The weather map and the base shape read aperiodically (noise.hpp, hex_taps), about the
    // channels' means over their textures; slice_at: the footprints' slice, b = (pw, fbm_w,
    // peak), with base_at's taps.
    void weather_at(double u, double v, float* w) const;
    void base_at(double u, double v, double z, float* b) const;
    void slice_at(double u, double v, float* b) const;
    double weather_mean_[4] = {}, base_mean_[2] = {}, peak_mean_ = 0.0;
};

}  // namespace welkin
