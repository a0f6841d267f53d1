// SPDX-License-Identifier: Apache-2.0
// Equirectangular sky images (HDRIs), with the sun's disc.
//
// The image covers the whole sphere in Blender's Environment Texture mapping
// (equirect.hpp): width x width/2 pixels, top row (zenith) first, pixel centres. Every
// pixel's sky radiance comes from one call of the chosen SkyMethod with all the pixel
// directions at once (bands of rows only beyond 512 MiB of radiance: spectral images
// wider than 2048); then, unless switched off, the sun's disc is added.
//
// Units. RGB output: linear RGB of `color_space` (Rec.709 by default; color_space.hpp)
// in W m^-2 sr^-1 (color.hpp), the sky converted with
// lambda power -3 and the disc with 0 (Bruneton 2017's sky and sun conversions).
// Spectral output: W m^-2 sr^-1 nm^-1 per atmosphere wavelength. Both are multiplied by
// `exposure`, once, at the end.
//
// The disc. Its spectral radiance is E_sun T / Omega_sun times the Neckel & Labs limb
// darkening (sun.hpp), cut by the horizon, with T and the visible fraction of
// sun_radiometry. The disc (0.53 degrees across) is often smaller than a pixel, so it is
// not point-sampled at pixel centres: each pixel its cap can touch is supersampled finely
// enough to resolve the disc (at least ~8 samples across its radius), and the result is
// scaled so that the image's integral over the disc, sum of radiance x pixel solid angle
// (equirect_pixel_solid_angle), equals sun_radiometry's direct irradiance exactly, per
// wavelength. Seen at any resolution, the HDRI therefore lights a scene with the right
// amount of sunlight; pixels partly covered by the disc get a partial (antialiased) value.
// Leave the disc out (sun_disc = false) when a sun lamp lights the scene: energy must
// appear once.
//
// Clouds (optional). With `clouds` set, every pixel's ray from the observer (the world
// origin, the planet centre straight below it) is also marched through the cloud density
// (clouds/lighting.hpp), lit by the same atmosphere (AtmosphereIllumination: the sun
// through the air at the cloud, the sky's mean radiance from the multiple-scattering LUT).
// The march gives the cloud's in-scattered radiance L_c (premultiplied), its transmittance
// T_c and the transmittance-weighted depth d_c of its scattering. The air between the
// observer and the cloud is applied as the camera cloud passes apply it (cloud_passes.hpp,
// the same function: aerial_along_rays, air_steps uniform steps to d_c). Along the ray,
// with the air's in-scattering S(a, b) and transmittance T(a, b), a cloud taken at d_c in
// front of the rest of the sky:
//     L = S(0, d_c) + T(0, d_c) [L_c + T_c S(d_c, inf)]
//       = T(0, d_c) L_c + (1 - T_c) S(0, d_c) + T_c [S(0, d_c) + T(0, d_c) S(d_c, inf)]
//       = T(0, d_c) L_c + (1 - T_c) S(0, d_c) + T_c L_sky,
// since the clear sky L_sky holds the air's whole path radiance S(0, inf) =
// S(0, d_c) + T(0, d_c) S(d_c, inf). (The sky method's S(0, inf) and the march's S(0, d_c)
// are two numerical integrals of the same air; their difference is the method's error.)
// This is the passes' Welkin.Clouds.rgb composited "over" the clear sky, so a panoramic
// camera's cloud passes over the clear HDRI give this image (tests/cpp/
// test_cloud_sky_image.cpp). Colour: in RGB output the composite is taken in the output space as
// the passes take it (the air's sunlit-surface RGB T(0, d_c) times the RGB cloud radiance,
// aerial_perspective.hpp); in spectral output per wavelength (T(lambda) L_c(lambda)). Where
// there is no air (T = 1, S = 0) this is the plain premultiplied "over" L_sky T_c + L_c.
// The cloud pass is upsampled (cloud_upsampling, lighting.hpp: by default one marched ray
// per 1.4 degrees, refined where the clouds have edges): the air is marched for the marched
// rays only, and each other pixel's cloud term T(0, d_c) L_c + (1 - T_c) S(0, d_c) is
// interpolated from its block's corners, as its T_c and L_c are.
// The cloud's depth extent is collapsed to d_c (the air inside one cloud is left out). The
// sun's disc is dimmed by T_c of its pixels. A procedural layer should be built with
// origin_altitude_m equal to the observer's altitude (the density source does not know
// the observer, so this is not checked).
//
// The ground. Views that meet the planet's surface (below the horizon) get, on top of the
// method's path radiance to the ground, T(x -> p) albedo / pi E(p) (ground.hpp: sun and
// sky irradiance of the ground point p, tabulated over the sun's zenith cosine there;
// T by quadrature per image row, which fixes the view's elevation and so the segment).
// From the ground the horizon is where the ground begins, with no gap; from higher up the
// ground near the horizon is seen through the long path that also lights the sky there.
//
// No NaN or infinity reaches the image: a method returning one is an error.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/clouds/lighting.hpp"
#include "welkin/color/color_space.hpp"
#include "welkin/sky/method.hpp"

namespace welkin {

struct SkyImageOptions {
    bool sun_disc = true;
    // The lit ground below the horizon (ground.hpp): the method's path radiance to the
    // ground plus the ground's own light through the air. Off: the path radiance alone
    // (a black ground).
    bool ground = true;
    // The ground's Lambertian albedo in [0, 1] at every wavelength; unset: the
    // atmosphere's ground_albedo.
    std::optional<double> ground_albedo;
    double exposure = 1.0;  // multiplies every output value; (0, 1e6]
    enum class Output { Rgb, Spectral };
    Output output = Output::Rgb;
    ColorSpace color_space = ColorSpace::Rec709;  // of RGB output
    std::shared_ptr<const CloudDensity> clouds;   // none: a clear sky
    CloudLightingOptions cloud_lighting;
    // The cloud pass is marched on a coarser grid and upsampled where smooth (lighting.hpp).
    CloudUpsampling cloud_upsampling;
    // Steps of the air's march from the observer to each cloud (a scene's
    // aerial.raymarch_steps); [1, 4096].
    int air_steps = 64;

    void validate() const;
};

struct SkyImage {
    int width = 0, height = 0;
    // "R", "G", "B"; or, for spectral output, one channel per wavelength named as in the
    // spectral OpenEXR layout of Fichet, Pacanowski & Wilkie 2021 ("An OpenEXR layout for
    // spectral images", JCGT 10(3)): emissive "S0.<wavelength>nm", decimal comma.
    std::vector<std::string> channel_names;
    std::vector<double> wavelengths_nm;  // of the spectral channels (empty for RGB)
    std::vector<float> pixels;           // (height, width, channels), top row first
    // With clouds: their transmittance per pixel, (height, width), top row first (the
    // factor the disc is dimmed by), for hosts that keep the disc in an image of its own;
    // empty without clouds.
    std::vector<float> cloud_transmittance;

    std::size_t channels() const { return channel_names.size(); }
};

// `width`: even, in [4, 16384]; the height is width / 2. Throws InvalidArgument on bad
// input, Cancelled when `progress` cancels, std::runtime_error when the method returns a
// non-finite radiance.
SkyImage render_equirect_sky(const SkyMethod& method, const Atmosphere& atmosphere, const Observer& observer,
                             int width, const SkyImageOptions& options = {}, Progress* progress = nullptr);

// A further sun lighting the same sky, without a disc: in `direction` (Z up), its
// irradiance at the top of the atmosphere `irradiance_scale` times the atmosphere's solar
// irradiance at every wavelength (the moon, sunlight it reflects: night/moonlit_sky.hpp).
// Every method's radiance and the lit ground are linear in the solar irradiance, so its
// sky is the method's sky for a sun there, times the scale.
struct ExtraSun {
    glm::dvec3 direction{0.0, 0.0, 1.0};
    double irradiance_scale = 0.0;  // >= 0, finite
};

// render_equirect_sky plus the skies of `extra` suns, in one pass over the image: per band
// of rows, the method's radiance and the lit ground of each sun, then per pixel each sun's
// spectrum converted to RGB and brought into the gamut on its own (as separate images
// would be) and summed, times the scale. The image equals render_equirect_sky for the
// observer's sun plus, per extra sun, irradiance_scale x render_equirect_sky for a sun in
// its direction with sun_disc off, up to float rounding; the directions, the pixels and
// the conversion are shared, and each extra sun costs its radiance and ground only.
// Not with clouds (the clouds would be lit by the observer's sun alone): InvalidArgument
// naming extra_suns; likewise for a zero or non-finite direction or a negative scale.
SkyImage render_equirect_sky(const SkyMethod& method, const Atmosphere& atmosphere, const Observer& observer,
                             std::span<const ExtraSun> extra, int width, const SkyImageOptions& options = {},
                             Progress* progress = nullptr);

// Spectral channel name for a wavelength, e.g. 550 -> "S0.550nm", 550.5 -> "S0.550,5nm".
std::string spectral_channel_name(double wavelength_nm);

}  // namespace welkin
