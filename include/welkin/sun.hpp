// The sun as seen from the observer: transmittance, direct irradiance, and the disc.
//
// Direct irradiance is the normal-incidence spectral irradiance the sun's disc delivers
// at the observer (what a Blender sun lamp's strength means, in W m^-2 per nm here):
// E_sun * T(observer -> sun) * the fraction of the disc above the horizon.
// Limb darkening follows Neckel & Labs 1994 ("The solar radiation between 3300 and
// 12500 A", Solar Physics 153) polynomial in mu = cos(angle from the disc centre).
#pragma once

#include <vector>

#include "welkin/sky_method.hpp"

namespace welkin {

struct SunRadiometry {
    std::vector<double> transmittance;        // per channel, at the disc centre
    std::vector<double> direct_irradiance;    // W m^-2 nm^-1 per channel
    double visible_fraction = 1.0;            // of the disc above the horizon
};

SunRadiometry sun_radiometry(const Atmosphere& atm, const Observer& observer);

// Limb-darkening factor relative to the disc's mean radiance, for a point at angular
// distance `angle_rad` from the disc centre of angular radius `radius_rad` (0 outside).
// Normalised so that its integral over the disc's solid angle equals the solid angle.
double limb_darkening(double angle_rad, double radius_rad, double wavelength_nm);

}  // namespace welkin
