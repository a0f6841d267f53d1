// SPDX-License-Identifier: Apache-2.0
// The sky of a moment with the moon: the sun's sky plus the moon's, and the moon's disc
// with its phase.
//
// Moonlight is sunlight reflected by the moon (astro/moonlight.hpp): at the top of the
// atmosphere its spectrum is the sun's times a constant, the irradiance ratio (Allen's
// magnitude-phase law). The air scatters and absorbs it as it does sunlight, so the
// moonlit sky is the sky the same SkyMethod gives for a sun in the moon's direction with
// the solar irradiance scaled by that ratio (the method's LUTs are reused, nothing is
// refitted), and the ground below the horizon is lit by it in the same way. Radiance
// adds: the image is render_equirect_sky for the sun (its disc included) plus the same for
// that dimmer "sun" without its disc, plus the moon's disc. Without clouds both skies are
// rendered in one pass over the image (render_equirect_sky with an ExtraSun: shared
// directions, pixels and conversion; the same image to float rounding); with clouds the
// moon's is a render of its own, its clouds lit by the moon.
//
// The moon's disc. Across the disc the radiance follows the Lommel-Seeliger law
// (moon_disc_relative_radiance: zero beyond the terminator, so the phase shows), times the
// atmosphere's transmittance towards the moon's centre per wavelength (sun_radiometry for
// the moon's direction). Like the sun's disc it is not point-sampled: every pixel the
// disc's bounding cap touches is supersampled at least 8 times across the disc's radius
// in elevation and azimuth, and the samples are scaled so that the image's integral over
// the whole lit disc, sum of radiance x pixel solid angle, equals the moon's irradiance at
// the observer, E_sun(lambda) x ratio x T(lambda), per wavelength; samples behind the
// ground are dropped (a setting moon loses that part of its light). With clouds its
// pixels are dimmed by the clouds' transmittance there, as the sun's are.
//
// Clouds (options.clouds). The cloud march and the composite over the sky
// (render/sky_image.hpp, "Clouds") are linear in the light as well: the clouds'
// in-scattered radiance L_c and the air's S(0, d_c) scale with the solar irradiance, while
// their transmittance T_c, depth d_c and the air's T(0, d_c) do not depend on the light.
// So the clouds lit by the moon are the clouds the same march gives for a "sun" in the
// moon's direction (its shadow rays, its diffusion along the moon's line) times the
// ratio, and the two composites add: the moon's image marches them once more, lit from the
// moon, with the same seeds and upsampling. While the sun is up (moon_clouds_left_out)
// that second march is skipped: the moon's clear sky is only seen through the clouds,
// times T_c, as the stars and the night glow are (stars.hpp, night_glow.hpp).
#pragma once

#include <glm/vec3.hpp>

#include "welkin/astro/positions.hpp"
#include "welkin/render/sky_image.hpp"

namespace welkin {

struct Moon {
    glm::dvec3 direction{0.0, 0.0, 1.0};      // towards the moon's (apparent) centre, Z up
    glm::dvec3 sun_from_moon{0.0, 0.0, 1.0};  // from the moon towards the sun (lights the disc)
    double angular_radius_rad = 0.0045;       // of the disc as seen
    double irradiance_ratio = 0.0;            // moon / sun irradiance at the top of the air, >= 0
    bool disc = true;                         // draw the disc (off: a moon lamp lights the scene)

    void validate() const;  // InvalidArgument naming moon.<field>
};

// The moon of a place and a moment (astro/positions.hpp, +Y north): its apparent
// direction, the sun's direction from it, its apparent radius and its brightness
// (moon_irradiance_ratio for its phase angle and its distances from the observer and
// from the sun).
Moon moon_at(const SunAndMoon& sky);

// Below this depression the moon's sky is left out (its disc is hidden anyway): the sky of
// a sun 20 degrees down (past the end of astronomical twilight, 18) is within a few times
// the night sky's own glow (night_glow.hpp) even just above the horizon below it, and the
// moon's is that times its irradiance ratio (< 3e-6): under 1e-4 of the glow
// (tests/cpp/test_moonlight.cpp). It saves a second sky render on most moonless nights.
inline constexpr double kMoonSkyDepressionDeg = 20.0;

// Whether the moon's light on the clouds is left out for this observer: while the sun's
// centre is above the horizon. Then the moon's irradiance (at most 3e-6 of the sun's,
// a full moon at perigee) lights the clouds far less than the sun does even at the
// horizon, where the air passes a few per cent of it: the moonlit clouds are under 1e-3
// of the sunlit ones (tests/cpp/test_night_clouds.cpp measures it).
inline bool moon_clouds_left_out(const Observer& observer) { return observer.sun_direction.z > 0.0; }

// The sun's sky (and disc, per options.sun_disc) plus the moon's sky and disc. Same
// options, units, exposure and errors as render_equirect_sky.
SkyImage render_equirect_sky_with_moon(const SkyMethod& method, const Atmosphere& atmosphere,
                                       const Observer& observer, const Moon& moon, int width,
                                       const SkyImageOptions& options = {}, Progress* progress = nullptr);

// The moon's disc alone, as the (height, width, channels) values it adds (before the
// exposure): for tests and for hosts that keep the disc in an image of their own.
std::vector<float> moon_disc_pixels(const Atmosphere& atmosphere, const Observer& observer, const Moon& moon,
                                    int width, SkyImageOptions::Output output);

// The moon's disc as a formula of the view direction v, for hosts that draw it themselves
// (the Blender add-on's world nodes, which show it to camera rays while a moon lamp lights
// the scene): where v is above the horizon,
//     L(v) = radiance_scale[c] x moon_disc_relative_radiance_far(v, ...)   (astro/moonlight.hpp),
// radiance_scale = E_sun(lambda) x irradiance_ratio x T(lambda) / relative_integral_sr,
// with T the transmittance towards the moon (as moon_disc_pixels) and relative_integral_sr
// = moon_disc_relative_integral_far: the disc's integral is the moon's irradiance at the
// observer, as the image's is. Before the exposure; spectral, per wavelength.
struct MoonDiscModel {
    std::vector<double> radiance_scale;  // W m^-2 sr^-1 nm^-1 per unit relative radiance
    double relative_integral_sr = 0.0;   // 0 at a new moon (then the scale is 0)
    double phase_angle_rad = 0.0;
};
MoonDiscModel moon_disc_model(const Atmosphere& atmosphere, const Observer& observer, const Moon& moon);

}  // namespace welkin
