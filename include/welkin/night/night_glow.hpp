// SPDX-License-Identifier: Apache-2.0
// The night sky's own light: airglow, zodiacal light and the unresolved stars together, as
// the moonless sky's brightness at a dark site.
//
// Brightness: Krisciunas & Schaefer 1991 ("A model of the brightness of moonlight", PASP
// 103, 1033, eqs. 1-2), the dark-time sky at the zenith of a dark site, B_zen = 21.587 V
// mag/arcsec^2 (79 nanoLamberts, Mauna Kea; within the 21.5-22 measured at dark sites,
// e.g. Benn & Ellison 1998, La Palma 21.9), brightening towards the horizon as the light of
// a thin emitting layer seen obliquely (van Rhijn 1921), X = (1 - 0.96 sin^2 z)^(-1/2),
// and dimmed by the air between the layer and the observer. B_zen is measured through the
// air at the zenith, so here
//     L(z, lambda) = L_zen(lambda) X(z) T(z, lambda) / T(0, lambda),
// with T the transmittance to the top of the atmosphere of the scene's Atmosphere
// (replacing K&S's fixed extinction coefficient; the layer, at ~ 100 km, is above the air).
// V magnitudes per arcsec^2 to radiance: V = 0 is 3.631e-11 W m^-2 nm^-1 at 545 nm
// (Bessell, Castelli & Plez 1998) and 1 sr is 4.2545e10 arcsec^2.
//
// Colour: airglow's lines (O I 557.7 nm, Na 589 nm, OH bands) are not resolved; the
// spectrum is taken as the sun's (the atmosphere's solar_irradiance), the colour of
// zodiacal light, normalised to the V radiance at 545 nm. The light the glow's own
// scattering adds back on the way down, and its dependence on the solar cycle (airglow
// doubles from solar minimum to maximum) and on ecliptic latitude (zodiacal light), are
// left out.
#pragma once

#include <vector>

#include "welkin/render/sky_image.hpp"

namespace welkin {

// K&S 1991's dark-sky brightness at the zenith, V mag/arcsec^2.
inline constexpr double kDarkSkyZenithVMagArcsec2 = 21.587;

// Spectral radiance (W m^-2 sr^-1 nm^-1) of a V surface brightness (mag/arcsec^2) at
// 545 nm.
double v_surface_brightness_to_radiance(double v_mag_per_arcsec2);

// The glow as the (height, width, channels) values it adds to an equirectangular image
// (before the exposure): 0 for rays that hit the ground. Same width rules and errors as
// render_equirect_sky.
std::vector<float> night_glow_pixels(const Atmosphere& atmosphere, const Observer& observer, int width,
                                     SkyImageOptions::Output output,
                                     ColorSpace color_space = ColorSpace::Rec709);

// Adds night_glow_pixels x exposure x the clouds' transmittance (with clouds) to an image
// render_equirect_sky made with the same options.
void add_night_glow(SkyImage& image, const Atmosphere& atmosphere, const Observer& observer,
                    const SkyImageOptions& options);

}  // namespace welkin
