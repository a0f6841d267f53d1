// SPDX-License-Identifier: Apache-2.0
// The night sky's own light, in its two main sources: the airglow of the upper atmosphere
// and the zodiacal light of the interplanetary dust, each dimmed by the air towards each
// direction.
//
// Airglow: a thin emitting layer at kAirglowHeight_m (the O I 557.7 nm layer at ~ 97 km,
// the Na and OH layers at ~ 92 and ~ 87 km), seen obliquely: a path through a shell of
// thickness dh at zenith angle z, from an observer at radius r under a layer at radius
// r_l, is dh / sqrt(1 - (r / r_l)^2 sin^2 z) long, so the radiance grows by van Rhijn's
// factor (van Rhijn 1921; Roach & Gordon 1973, "The Light of the Night Sky", eq. 3.1)
//     V(z) = 1 / sqrt(1 - (r / r_l)^2 sin^2 z).
// Its spectrum at the zenith, above the air: the emissions that fall in the visible, with
// the intensities usually quoted for a mid-latitude night of average solar activity
// (Leinert et al. 1998, "The 1997 reference of diffuse night sky brightness", A&AS 127,
// 1, their airglow section and Fig. 1; Roach & Gordon 1973): the O I green line 557.7 nm,
// 250 R; the Na D doublet 589.0/589.6 nm, 50 R (20 R in summer to 150 R in winter); the
// O I red lines 630.0 and 636.4 nm, 60 and 20 R; and the pseudo-continuum (NO2 and
// unresolved bands), 3 R/nm (0.3 R/A) flat in photons. 1 R (rayleigh) is 10^10/(4 pi)
// photons s^-1 m^-2 sr^-1. The OH Meinel bands are almost all beyond 700 nm, where the
// eye's and the colour-matching functions' sensitivity is under 0.4 % of its peak: left
// out. Airglow doubles from solar minimum to maximum (Krisciunas 1997, PASP 109, 1181):
// these are mid-cycle values.
//
// Lines on the Atmosphere's wavelengths (4 by default, or a spectral grid): the spectrum
// the channels stand for is their linear interpolant (color/color.hpp), whose integral is
// sum_c L_c w_c with w_c the half-distance between channel c's neighbours (the end
// channels: half the distance to their one neighbour). A line of radiance R at lambda
// between channels a and b adds R f / w_a to a and R (1 - f) / w_b to b (f = (lambda_b -
// lambda) / (lambda_b - lambda_a)): the interpolant's integral gains exactly R. A line
// beyond the end channels adds R / w to the nearer end one (the default channels end at
// 620 nm: the O I red lines go there).
//
// Zodiacal light: Leinert et al. 1998, Table 16: the brightness seen from the Earth in
// S10 units (the light of one star of V = 10 per square degree, of the sun's colour) by
// helioecliptic longitude lambda - lambda_sun (0-180 degrees) and ecliptic latitude beta
// (0-75 degrees); towards the ecliptic pole 60 S10 (their text beside Table 16),
// interpolated bilinearly in |lambda - lambda_sun| and |beta|. The table's cells within
// 15 degrees of the sun are empty (the solar corona's F component): they hold the value
// of the nearest filled cell at the same latitude (never above the horizon at night; in
// twilight the scattered sunlight outshines them by orders of magnitude). 1 S10 at
// 500 nm is the radiance of V = 10 mag per square degree at 545 nm times the sun's
// spectrum's ratio 500/545 nm. Spectrum: the sun's (the Atmosphere's solar_irradiance),
// reddened as Leinert et al. 1998 give it (the colour section; the form of Noll et al.
// 2012, A&A 543, A92, Sect. 3.3): f_co(lambda) = 1 + a ln(lambda / 500 nm), a = 1.2
// below 500 nm and 0.8 above at elongation 30 degrees, 0.9 and 0.6 at 90 degrees and
// beyond, linear between. The directions' ecliptic coordinates: astro/positions.hpp's
// ecliptic_frame (ERFA) for the moment and place; the image evaluates the table on nodes
// every few pixels (1.4 degrees apart at most) and interpolates bilinearly between them.
//
// Through the air: each part times the transmittance T(z, lambda) from the observer to
// the top of the atmosphere of the scene's Atmosphere (the layer and the dust are above
// the air). The light the air scatters into the line of sight from the glow of the rest
// of the sky (which gives back part of what the extinction takes), the integrated light
// of the stars fainter than the catalogue's V 7 and the diffuse galactic light (10-20 %
// of the dark zenith at high galactic latitude, Leinert et al. 1998) are left out.
//
// V magnitudes per arcsec^2 to radiance: V = 0 is 3.631e-11 W m^-2 nm^-1 at 545 nm
// (Bessell, Castelli & Plez 1998) and 1 sr is 4.2545e10 arcsec^2.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "welkin/astro/positions.hpp"
#include "welkin/render/sky_image.hpp"

namespace welkin {

// What the parts add up to at the zenith of a dark site is checked against the measured
// dark sky, 21.5-22 V mag/arcsec^2 (Krisciunas & Schaefer 1991, PASP 103, 1033, Mauna
// Kea, 21.587; Benn & Ellison 1998, La Palma, 21.9): tests/python/test_night_sky.py,
// docs/validation.md.

// Height of the airglow layer above the ground.
inline constexpr double kAirglowHeight_m = 97e3;

// The airglow's lines at the zenith above the air and its continuum (header comment).
struct AirglowLine {
    double lambda_nm, rayleigh;
};
std::span<const AirglowLine> airglow_lines();
inline constexpr double kAirglowContinuumRayleighPerNm = 3.0;

// Spectral radiance (W m^-2 sr^-1 nm^-1) of a V surface brightness (mag/arcsec^2) at
// 545 nm.
double v_surface_brightness_to_radiance(double v_mag_per_arcsec2);

// Van Rhijn's factor of a layer at radius layer_radius_m seen from radius
// observer_radius_m at zenith angle acos(cos_zenith) (header comment).
double van_rhijn_factor(double cos_zenith, double observer_radius_m, double layer_radius_m);

// The airglow's spectral radiance at the zenith above the air (W m^-2 sr^-1 nm^-1) on
// the channels `wavelengths_nm` (strictly monotonic), lines spread as the header says.
std::vector<double> airglow_zenith_radiance(std::span<const double> wavelengths_nm);

// Leinert et al. 1998's zodiacal light (S10) at helioecliptic longitude and ecliptic
// latitude (degrees; any value: folded to |lambda - lambda_sun| in [0, 180] and |beta|).
double zodiacal_light_s10(double helioecliptic_longitude_deg, double ecliptic_latitude_deg);

// What the glow is made of, and where the ecliptic is.
struct NightGlowOptions {
    // The ecliptic in the image's frame (astro/positions.hpp's ecliptic_frame; a host that
    // turns the sky turns enu_to_ecliptic alike). None: the zodiacal light at its darkest,
    // the ecliptic pole's 60 S10, everywhere.
    std::optional<EclipticFrame> ecliptic;
    bool airglow = true;
    bool zodiacal_light = true;
};

// The glow as the (height, width, channels) values it adds to an equirectangular image
// (before the exposure): 0 for rays that hit the ground. Same width rules and errors as
// render_equirect_sky.
std::vector<float> night_glow_pixels(const Atmosphere& atmosphere, const Observer& observer, int width,
                                     SkyImageOptions::Output output,
                                     ColorSpace color_space = ColorSpace::Rec709,
                                     const NightGlowOptions& glow = {});

// Adds night_glow_pixels x exposure x the clouds' transmittance (with clouds) to an image
// render_equirect_sky made with the same options.
void add_night_glow(SkyImage& image, const Atmosphere& atmosphere, const Observer& observer,
                    const SkyImageOptions& options, const NightGlowOptions& glow = {});

}  // namespace welkin
