// SPDX-License-Identifier: Apache-2.0
// The sun as seen from the observer: transmittance, direct irradiance, and the disc.
//
// Direct irradiance is the normal-incidence spectral irradiance the sun's disc delivers
// at the observer (what a Blender sun lamp's strength means, in W m^-2 per nm here):
// E_sun * T(observer -> sun) * the fraction of the disc above the horizon.
// Limb darkening follows Neckel & Labs 1994 ("The solar radiation between 3300 and
// 12500 A", Solar Physics 153) polynomial in mu = cos(angle from the disc centre).
#pragma once

#include <array>
#include <vector>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/observer.hpp"

namespace welkin {

struct SunRadiometry {
    // Per channel, along the disc centre; when the horizon cuts the disc, along the middle
    // of its visible part (a grazing ray through the centre would be far too dark); 0 when
    // the whole disc is below the horizon.
    std::vector<double> transmittance;
    std::vector<double> direct_irradiance;  // W m^-2 nm^-1 per channel
    // Of the disc's area above the horizon of a spherical ground at the observer's
    // altitude (the horizon is a straight chord across the small disc).
    double visible_fraction = 1.0;
};

SunRadiometry sun_radiometry(const Atmosphere& atm, const Observer& observer);

// Neckel & Labs 1994's a_0..a_5 at a wavelength (I(mu) / I(1) = sum_k a_k mu^k, summing
// to 1), interpolated linearly between their 30 continuum windows, the end rows outside
// [303, 1099] nm.
std::array<double, 6> limb_darkening_coefficients(double wavelength_nm);

// Limb-darkening factor relative to the disc's mean radiance, for a point at angular
// distance `angle_rad` from the disc centre of angular radius `radius_rad` (0 outside).
// Normalised so that its integral over the disc's solid angle equals the solid angle.
double limb_darkening(double angle_rad, double radius_rad, double wavelength_nm);

// The same, with the coefficients and the normalisation computed once for one wavelength
// and one disc radius: for loops over many directions (the sun disc in a sky image).
class LimbDarkening {
public:
    LimbDarkening(double radius_rad, double wavelength_nm);
    double operator()(double angle_rad) const;
    // Ratio of the centre radiance to the disc's mean radiance.
    double centre() const { return coefficients_sum_ / mean_; }

private:
    double radius_rad_, sin_radius_;
    double a_[6];
    double coefficients_sum_;
    double mean_;  // mean over the disc's solid angle of sum a_k mu^k
};

}  // namespace welkin
