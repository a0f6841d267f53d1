// A procedural cloud layer on the curved planet, after Schneider's Nubis clouds
// (Schneider 2015, "The real-time volumetric cloudscapes of Horizon Zero Dawn", SIGGRAPH
// Advances in Real-Time Rendering; Schneider 2017, "Nubis: authoring real-time volumetric
// cloudscapes with the Decima engine"; GPU Pro 7, ch. 4 "Real-time volumetric cloudscapes").
//
// The layer is the spherical shell between bottom_altitude_m and top_altitude_m above a
// ground of radius planet_radius_m, whose centre is straight below the world origin
// (which stands origin_altitude_m above the ground, DESIGN.md). At a point p with
// altitude h and height fraction f = (h - bottom) / (top - bottom):
//   weather map (2D, tiling every weather_scale_m):   coverage c and type t at (x, y),
//       c = coverage * clamp(1 + weather_variation (2 w_r - 1)), t = clamp(cloud_type
//       + type_variation (2 w_g - 1)), w the weather texture (Perlin fBm);
//   base shape (3D, tiling every base_scale_m):  base = remap(pw, -(1 - fbm_w), 1, 0, 1),
//       pw the Perlin-Worley channel, fbm_w = 0.625 g + 0.25 b + 0.125 a its Worley octaves;
//   height gradient G(t, f): a trapezoid per cloud type, stratus (thin, low), stratocumulus,
//       cumulus (tall), blended linearly in t (0 stratus, 0.5 stratocumulus, 1 cumulus);
//   coverage: base' = remap(base G, 1 - c, 1, 0, 1) c  (more coverage: more of the
//       noise above the threshold, Schneider's "remap by coverage");
//   detail erosion (3D, tiling every detail_scale_m): the Worley fBm of the detail
//       texture, inverted towards the top (wispy bottoms, billowy tops), erodes the edges:
//       density = remap(base', detail_strength * mix(fbm_d, 1 - fbm_d, clamp(10 f)), 1, 0, 1);
//   sigma_t = density_per_m * clamp(density, 0, 1).
// Noise coordinates are the world x, y (minus the wind offset) and the altitude, all
// divided by the tile's scale: the field tiles horizontally and follows the planet's
// curvature vertically. Every remap keeps values <= its input when the input is <= 1, so
// density <= c <= coverage: the majorant is density_per_m * coverage on the shell.
// The gradient trapezoids' corners are Welkin's choice, in the spirit of Schneider's
// hand-drawn gradients (GPU Pro 7, fig. 4.7): they are parameters of look, not physics.
//
// Deterministic: the noise is baked from the seed by integer hashing (cloud_noise.hpp),
// the same on every machine.
#pragma once

#include <cstdint>
#include <memory>

#include <glm/vec2.hpp>

#include "welkin/clouds/density.hpp"
#include "welkin/clouds/noise.hpp"

namespace welkin {

struct CloudLayerParams {
    double bottom_altitude_m = 1500.0;   // [0, 20000), below top
    double top_altitude_m = 3000.0;      // (bottom, 20000]
    double coverage = 0.5;               // [0, 1]
    double cloud_type = 1.0;             // [0, 1]: 0 stratus, 0.5 stratocumulus, 1 cumulus
    double density_per_m = 0.03;         // sigma_t of the densest cloud, m^-1, [0, 10]
    double base_scale_m = 6000.0;        // tile of the base shape, [10, 1e6] m
    double detail_scale_m = 800.0;       // tile of the erosion noise, [1, 1e6] m
    double weather_scale_m = 40000.0;    // tile of the weather map, [10, 1e7] m
    double detail_strength = 0.35;       // [0, 1]
    double weather_variation = 0.5;      // [0, 1]
    double type_variation = 0.0;         // [0, 1]
    glm::dvec2 wind_offset_m{0.0, 0.0};  // shifts the field by this much (finite)
    std::uint64_t seed = 1;
    double planet_radius_m = 6360e3;     // [1e3, 1e8]
    double origin_altitude_m = 0.0;      // of the world origin above the ground, [0, 1e6]

    void validate() const;  // InvalidArgument naming the field and its range
};

class ProceduralClouds final : public CloudDensity {
public:
    explicit ProceduralClouds(const CloudLayerParams& params);

    double sigma_t(const glm::dvec3& p) const override;
    void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const override;
    double feature_size_m() const override;

    const CloudLayerParams& params() const { return p_; }

    // Height gradient G(type, f) of the header, for f in [0, 1] (0 outside).
    static double height_gradient(double type, double f);

private:
    CloudLayerParams p_;
    glm::dvec3 centre_;
    std::shared_ptr<const CloudNoiseTextures> noise_;
    // The channels sigma_t reads, combined once: base (pw, fbm_w), detail fbm_d, weather (r, g).
    PeriodicTexture<2> base_, weather_;
    PeriodicTexture<1> detail_;
    double inv_weather_ = 0.0, inv_base_ = 0.0, inv_detail_ = 0.0;  // 1 / the tile scales
};

}  // namespace welkin
