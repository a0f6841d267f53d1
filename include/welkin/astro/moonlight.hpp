// SPDX-License-Identifier: Apache-2.0
// The moon as a light source at the top of the atmosphere: how bright its disc is, as a
// fraction of the sun's light, and how that light spreads over the disc.
//
// Brightness: the Moon's integrated V magnitude against its phase angle alpha (degrees;
// 0 full, 180 new) at its mean distance, 384400 km, and 1 au from the Sun,
//     V(alpha) = -12.73 + 0.026 |alpha| + 4e-9 alpha^4
// (Allen, "Astrophysical Quantities", 3rd ed. 1973, section 66, the fit Krisciunas &
// Schaefer 1991, "A model of the brightness of moonlight", PASP 103, 1033, eq. 9 use),
// against the Sun's V = -26.74 at 1 au (Allen). The moon's irradiance at the observer is
// then the sun's at 1 au times
//     ratio = 10^(-0.4 (V(alpha) + 26.74)) (384400 km / d_moon)^2 (1 au / d_sun_moon)^2.
// Moonlight is taken with the sun's spectrum: the lunar surface's reddening (its
// reflectance rises by some 50 % from 450 to 700 nm) is left out, so a moonlit sky is the
// same atmosphere lit by a dimmer sun from the moon's direction.
//
// Across the disc: the Lommel-Seeliger law, radiance proportional to mu0 / (mu0 + mu)
// (mu0, mu: cosines of the incidence and emission angles at a point of the lunar sphere),
// zero on the night side; the phase's terminator comes from mu0 = 0. (A Lommel-Seeliger
// sphere alone falls off with phase far slower than the Moon does, which is why the
// brightness comes from the magnitude law and only the spread from the surface law.)
#pragma once

#include <array>

namespace welkin {

// Allen's V magnitude of the Moon at phase angle alpha (degrees, |alpha| <= 180), mean
// distances. InvalidArgument naming phase_angle_deg outside [0, 180] or non-finite.
double moon_v_magnitude(double phase_angle_deg);

// Moon irradiance / solar irradiance at 1 au (wavelength-independent), for the observer
// at moon_distance_m from the moon, the moon at sun_distance_m from the sun.
double moon_irradiance_ratio(double phase_angle_deg, double moon_distance_m, double sun_distance_m);

// Relative radiance (Lommel-Seeliger, unnormalised) of the point of the moon's visible
// disc seen in direction `view` (unit, from the observer), for the moon's centre in
// direction `moon` (unit) at angular radius `radius_rad`, lit from direction `sun_from_moon`
// (unit, from the moon towards the sun). 0 off the disc and on its night side.
double moon_disc_relative_radiance(const std::array<double, 3>& view, const std::array<double, 3>& moon,
                                   double radius_rad, const std::array<double, 3>& sun_from_moon);

// The same seen from far away (the moon's distance >> its radius, to first order in the
// angular radius): with the view at angle rho from the centre, s = sin(rho) / sin(radius),
// mu = sqrt(1 - s^2) and, from the sphere's point n = -mu m + (v - (v.m) m) / sin(radius),
//     mu0 = n . sun_from_moon = ((v x m) . (sun_from_moon x m)) / sin(radius) - mu (m . sun_from_moon),
// radiance mu0 / (mu0 + mu) where mu0 > 0 and s < 1, else 0. This is what a host that
// draws the disc from the view direction in single precision evaluates (the add-on's world
// nodes: a cross product, no cancellation); it differs from the exact form by under 1 %
// of the radiance.
double moon_disc_relative_radiance_far(const std::array<double, 3>& view, const std::array<double, 3>& moon,
                                       double radius_rad, const std::array<double, 3>& sun_from_moon);

// The integral of moon_disc_relative_radiance_far over the disc, in sr: the Lommel-Seeliger
// sphere's disc-integrated brightness, sin^2(radius) pi/2 Phi(g), with its phase function
//     Phi(g) = 1 - sin(g/2) tan(g/2) ln cot(g/4)
// (Phi(0) = 1: the full disc's mean relative radiance is 1/2; Phi(180) = 0), g the phase
// angle: the angle at the moon between the sun and the observer,
// cos g = -(m . sun_from_moon). (Derivation: integrate mu0 mu / (mu0 + mu) over the lit,
// visible hemisphere in the luminous-equator frame, e.g. Fairbairn 2005, "Planetary
// photometry: the Lommel-Seeliger law", JRASC 99, 92.) InvalidArgument naming radius_rad
// outside (0, 0.05] or a non-finite phase.
double moon_disc_relative_integral_far(double phase_angle_rad, double radius_rad);

}  // namespace welkin
