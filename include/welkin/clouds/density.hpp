// SPDX-License-Identifier: Apache-2.0
// Cloud density sources: the one interface every cloud medium answers.
//
// As in pbrt-v4 (Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., ch. 11),
// a medium only says how dense it is: the extinction coefficient sigma_t(p) at a point,
// and, for a ray, the pieces of the ray where sigma_t may be non-zero together with an
// upper bound (the majorant) of sigma_t on each piece. The integrators (clouds/lighting.hpp,
// the fast march; clouds/reference.hpp, the path tracer) do all the marching, for every
// source alike: the fast march steps only through the pieces (empty-space skipping), the
// path tracer samples free paths against the majorants (delta and ratio tracking).
//
// Units: points in Blender's world frame (Z up, metres; the planet centre straight below
// the origin, docs/design.md), sigma_t in m^-1. Cloud droplets scatter visible light almost
// without absorbing it and without depending on wavelength (Mie regime, droplets ~10 um):
// extinction is grey, and the single-scattering albedo is a lighting parameter.
//
// Thread safety: a source is immutable after construction; any number of threads may
// query it at once.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

namespace welkin {

struct CloudRay {
    glm::dvec3 origin;     // world frame, m
    glm::dvec3 direction;  // unit vector
    glm::dvec3 at(double t) const { return origin + t * direction; }
};

// [t0, t1] along a ray on which sigma_t <= majorant (m^-1); outside every segment of a
// query, sigma_t is zero.
struct MajorantSegment {
    double t0, t1, majorant;
};

class CloudDensity {
public:
    virtual ~CloudDensity() = default;

    // Extinction coefficient at world point p, m^-1, finite and >= 0.
    virtual double sigma_t(const glm::dvec3& p) const = 0;

    // Appends to `out` the segments of [0, t_max] of `ray` where sigma_t may be non-zero,
    // in increasing t, not overlapping, each with its majorant. `out` is cleared first.
    virtual void segments(const CloudRay& ray, double t_max, std::vector<MajorantSegment>& out) const = 0;

    // A step length that resolves the density's structure (m): the fast march takes steps
    // no longer than this where the medium is dense.
    virtual double feature_size_m() const = 0;
};

// The segments of [t_lo, t_hi] of `ray` inside the axis-aligned box [lo, hi] (slab method,
// Kay & Kajiya 1986); false when the ray misses it.
bool clip_ray_to_box(const CloudRay& ray, const glm::dvec3& lo, const glm::dvec3& hi, double& t_lo,
                     double& t_hi);

}  // namespace welkin
