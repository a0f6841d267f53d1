// Equirectangular sky images (HDRIs), with the sun's disc.
//
// The image covers the whole sphere in Blender's Environment Texture mapping
// (equirect.hpp): width x width/2 pixels, top row (zenith) first, pixel centres. Every
// pixel's sky radiance comes from one call of the chosen SkyMethod with all the pixel
// directions at once (bands of rows only beyond 512 MiB of radiance: spectral images
// wider than 2048); then, unless switched off, the sun's disc is added.
//
// Units. RGB output: linear Rec.709 in W m^-2 sr^-1 (color.hpp), the sky converted with
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
// origin) is also marched through the cloud density (cloud_lighting.hpp), lit by the same
// atmosphere (AtmosphereIllumination: the sun through the air at the cloud, the sky's mean
// radiance from the multiple-scattering LUT), and composited over the sky per wavelength
// before any conversion: L = L_sky T_cloud + L_cloud (premultiplied "over"); the sun's
// disc is dimmed by T_cloud of its pixels. The air between the observer and the cloud
// (aerial perspective) is not applied to the cloud here. A procedural layer should be
// built with origin_altitude_m equal to the observer's altitude (the density source does
// not know the observer, so this is not checked).
//
// No NaN or infinity reaches the image: a method returning one is an error.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "welkin/cloud_lighting.hpp"
#include "welkin/sky_method.hpp"

namespace welkin {

struct SkyImageOptions {
    bool sun_disc = true;
    double exposure = 1.0;  // multiplies every output value; (0, 1e6]
    enum class Output { Rgb, Spectral };
    Output output = Output::Rgb;
    std::shared_ptr<const CloudDensity> clouds;  // none: a clear sky
    CloudLightingOptions cloud_lighting;

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
SkyImage render_equirect_sky(const SkyMethod& method, const Atmosphere& atmosphere,
                             const Observer& observer, int width,
                             const SkyImageOptions& options = {}, Progress* progress = nullptr);

// Spectral channel name for a wavelength, e.g. 550 -> "S0.550nm", 550.5 -> "S0.550,5nm".
std::string spectral_channel_name(double wavelength_nm);

}  // namespace welkin
