// SPDX-License-Identifier: Apache-2.0
// Reference cloud lighting: a volumetric path tracer, all scattering orders.
//
// The same question as render_clouds (clouds/lighting.hpp), for the same density, phase,
// albedo and illumination, answered without approximation, so that the fast march can be
// measured against it. The radiative transfer in the cloud is solved by Monte Carlo:
//
//  * Free paths by delta tracking (Woodcock et al. 1965; pbrt-v4 ch. 14.2, "SampleT_maj"),
//    against the piecewise-constant majorants of the density's segments: a tentative
//    collision every exponential(majorant) metres, kept as a real one with probability
//    sigma_t / majorant; a segment's end restarts the exponential (memoryless).
//  * At a real collision the path's weight is multiplied by the albedo, the sun is added
//    by next-event estimation: weight p(d . s) E(x) T_cloud(x -> sun), T_cloud by ratio
//    tracking (Cramer 1978; Novak et al. 2014, "Residual ratio tracking"), the product of
//    (1 - sigma_t / majorant) over the tentative collisions; then a new direction is
//    sampled from the phase function (exactly, so the weight is unchanged).
//  * A path leaving the cloud after at least one scattering picks up the sky radiance at
//    its last vertex from the hemisphere it leaves into (above or below that point's
//    horizon): the same sky as the fast march's, so both solve the same problem. (The view ray leaving
//    without scattering is the transmittance T, estimated separately by ratio tracking of the view ray: the
//    background is not ours.)
//  * No Russian roulette (albedo ~1 would not end paths); a path is cut after max_bounces
//    scatterings, and the fraction of paths cut is reported (truncated_fraction), which
//    bounds the energy lost.
// Random numbers: PathRng(seed, ray, path), so results do not depend on the thread count.
// Standard errors: the sample standard deviation over paths / sqrt(paths), per value.
#pragma once

#include "welkin/clouds/lighting.hpp"

namespace welkin {

struct CloudReferenceOptions {
    CloudScattering scattering;
    int paths = 256;         // per ray, [1, 1 << 24]
    int max_bounces = 4096;  // [1, 1 << 20]
    std::uint64_t seed = 1;
    double max_distance_m = 1e6;  // view rays end here, (0, 1e8]
    void validate() const;
};

struct CloudReferenceResult : CloudResult {
    double truncated_fraction = 0.0;  // of paths cut at max_bounces
};

// Depth is estimated as in render_clouds, from the ratio-tracked transmittance along the
// view ray (the expected distance to the first real collision, weighted by opacity).
CloudReferenceResult render_clouds_reference(const CloudDensity& density, const CloudIllumination& light,
                                             const glm::dvec3& origin, std::span<const glm::dvec3> directions,
                                             const CloudReferenceOptions& options = {},
                                             Progress* progress = nullptr);

}  // namespace welkin
