// SPDX-License-Identifier: Apache-2.0
// Ray geometry in a spherical planet, in double precision.
//
// A point is described by its distance r to the planet centre; a ray by the cosine mu of
// its angle with the local zenith. All distances are in metres. Planet-scale geometry
// loses float32 digits: r^2 - R^2 near the ground is a difference of two numbers near
// 4e13. These functions therefore use double and the cancellation-free factorisation
// r^2 - R^2 = (r - R)(r + R) (Bruneton 2017 sec. 2.1 writes the same discriminants).
#pragma once

#include "welkin/base/math.hpp"

namespace welkin {

// Discriminant of |p + t d| = radius for a ray starting at distance r with zenith cosine
// mu: r^2 mu^2 - (r^2 - radius^2), written without cancelling r^2 against radius^2.
inline double sphere_discriminant(double r, double mu, double radius) {
    return r * r * mu * mu - (r - radius) * (r + radius);
}

// Distance to the top of the atmosphere (radius `top`) from inside it (r <= top).
inline double distance_to_top(double r, double mu, double top) {
    return std::max(0.0, -r * mu + safe_sqrt(sphere_discriminant(r, mu, top)));
}

// Distance to the ground (radius `bottom`) along a ray that hits it (r >= bottom).
inline double distance_to_bottom(double r, double mu, double bottom) {
    return std::max(0.0, -r * mu - safe_sqrt(sphere_discriminant(r, mu, bottom)));
}

// True when the ray from (r, mu) hits the ground sphere.
inline bool ray_hits_ground(double r, double mu, double bottom) {
    return mu < 0.0 && sphere_discriminant(r, mu, bottom) >= 0.0;
}

// Distance along the ray to wherever it leaves the atmosphere: the ground if it hits it,
// else the top. Rays from above the atmosphere are first moved to their entry point by
// the caller (see enter_atmosphere).
inline double distance_to_boundary(double r, double mu, double bottom, double top) {
    return ray_hits_ground(r, mu, bottom) ? distance_to_bottom(r, mu, bottom) : distance_to_top(r, mu, top);
}

// Radius and zenith cosine at distance t along the ray (law of cosines).
inline double radius_at(double r, double mu, double t) {
    return std::sqrt(std::max(t * t + 2.0 * r * mu * t + r * r, 0.0));
}
inline double mu_at(double r, double mu, double t, double r_t) { return clamp_cosine((r * mu + t) / r_t); }

// For an observer above the top of the atmosphere (r > top): the distance to the point
// where the ray enters the atmosphere, or a negative value when the ray misses it.
inline double distance_to_atmosphere_entry(double r, double mu, double top) {
    const double disc = sphere_discriminant(r, mu, top);
    if (disc < 0.0 || mu >= 0.0) return -1.0;
    return std::max(0.0, -r * mu - std::sqrt(disc));
}

}  // namespace welkin
