// SPDX-License-Identifier: Apache-2.0
// The atmosphere: everything about the planet and its air that the sky depends on.
//
// All quantities are SI: lengths in metres, scattering and extinction coefficients in
// m^-1 (at relative density 1, see DensityProfile), irradiance in W m^-2 nm^-1. Spectral
// quantities are sampled at `wavelengths_nm`, one value per wavelength; the default is
// four samples, 620, 560, 480 and 440 nm (one SIMD batch of the fast methods, batch.hpp),
// converted to RGB by matrices fitted to the 48-wavelength path (color.cpp): within
// 0.0073 in CIE xy of it from day through twilight (docs/validation.md). Bruneton 2017
// and Hillaire 2020 use three, 680, 550 and 440 nm, which turn twilight magenta.
//
// The model is Bruneton 2017's (atmosphere/definitions.glsl, AtmosphereParameters):
// Rayleigh scattering (no absorption), Mie scattering and extinction, and an absorbing
// layer (ozone), each with its own density profile, over a Lambertian ground.
//
// An Atmosphere is plain data; validate() checks every field and throws InvalidArgument
// naming the field and its accepted range. Every factory (preset, from_json) validates,
// and every method validates again before it uses one.
#pragma once

#include <string>
#include <vector>

#include "welkin/atmosphere/density_profile.hpp"
#include "welkin/atmosphere/phase.hpp"

namespace welkin {

struct Atmosphere {
    std::string name = "custom";

    std::vector<double> wavelengths_nm;
    // Extraterrestrial solar spectral irradiance at the top of the atmosphere, normal
    // incidence, W m^-2 nm^-1.
    std::vector<double> solar_irradiance;
    double sun_angular_radius_rad = 0.004675;

    double bottom_radius_m = 6360e3;
    double top_radius_m = 6420e3;

    DensityProfile rayleigh_density;
    std::vector<double> rayleigh_scattering;  // m^-1; Rayleigh does not absorb

    DensityProfile mie_density;
    std::vector<double> mie_scattering;  // m^-1
    std::vector<double> mie_extinction;  // m^-1, >= mie_scattering
    MiePhaseModel mie_phase = MiePhaseModel::CornetteShanks;
    double mie_g = 0.8;

    DensityProfile absorption_density;
    std::vector<double> absorption_extinction;  // m^-1

    std::vector<double> ground_albedo;  // Lambertian, in [0, 1]

    std::size_t channels() const { return wavelengths_nm.size(); }
    double atmosphere_thickness_m() const { return top_radius_m - bottom_radius_m; }

    // Throws InvalidArgument on the first invalid field.
    void validate() const;

    // Total extinction (m^-1) of channel c at altitude h.
    double extinction(std::size_t c, double altitude_m) const;
    // Scattering (Rayleigh + Mie, m^-1) of channel c at altitude h.
    double scattering(std::size_t c, double altitude_m) const;

    // Built-in presets (see src/atmosphere/presets.cpp for each one's sources). `wavelengths_nm`
    // empty means the default four (620, 560, 480, 440 nm); any list of wavelengths in
    // [360, 830] nm resamples the preset's spectral models, which is how the spectral
    // mode gets many wavelengths.
    static Atmosphere preset(const std::string& name, const std::vector<double>& wavelengths_nm = {});
    // The default first (kDefaultPreset), then by the weather.
    static std::vector<std::string> preset_names();

    // JSON (the schema is documented in docs/pipelines.md, "Atmosphere JSON", and written by to_json).
    static Atmosphere from_json_string(const std::string& text);
    static Atmosphere from_json_file(const std::string& path);
    std::string to_json_string() const;
    // Refuses to overwrite an existing file unless `overwrite`.
    void to_json_file(const std::string& path, bool overwrite = false) const;

    // Every field equal (member by member, so a field added later takes part as well);
    // caches of what an atmosphere determines (lut_cache.hpp) use it as their key.
    bool operator==(const Atmosphere&) const = default;
};

// The preset of an atmosphere nobody chose: an ordinary clear day (presets.cpp).
inline constexpr const char* kDefaultPreset = "clear_day";

// The default channels: 620, 560, 480 and 440 nm (above).
const std::vector<double>& default_wavelengths_nm();
// Evenly spaced wavelengths for the spectral mode: 360..830 nm (48 samples at 10 nm,
// the range of the CIE 1931 functions and of the solar and ozone tables we carry).
std::vector<double> spectral_wavelengths_nm(double step_nm = 10.0);

}  // namespace welkin
