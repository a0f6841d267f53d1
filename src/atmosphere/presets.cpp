// SPDX-License-Identifier: Apache-2.0
// Built-in atmospheres. Each preset is a set of spectral models evaluated at the requested
// wavelengths, so the same preset serves the three-channel and the spectral paths.
//
// Shared Earth models:
//  * Rayleigh: beta_R(lambda) = 1.24062e-6 m^-1 (lambda / 1 um)^-4, exponential with an
//    8 km scale height (Bruneton 2017, atmosphere/demo/demo.cc; Bucholtz 1995's
//    sea-level coefficient with the lambda^-4 law).
//  * Ozone: 300 Dobson units in a tent from 10 km through 25 km to 40 km. The tent's
//    integral is 15 km, so the peak number density is 300 DU / 15 km, times the
//    Serdyuchenko 2014 cross-section (spectral_data.hpp).
//  * Aerosol (Mie): the aerosol types of OPAC (Hess, Koepke & Schult 1998, "Optical
//    Properties of Aerosols and Clouds: The Software Package OPAC", BAMS 79(5), 831-844,
//    Table 4, relative humidity 80 %): per type the vertical optical depth at 550 nm
//    tau_550, the single-scattering albedo omega and the asymmetry parameter g at
//    550 nm, the Angstrom exponents over 350-500 nm and 500-800 nm, and OPAC's height
//    profile, exp(-h / Z) through a mixing layer of height H (continental types Z = 8 km,
//    H = 2 km; desert Z = 2 km, H = 6 km; maritime Z = 1 km, H = 2 km). Welkin takes it as
//    one exponential with OPAC's surface extinction and column: scale height
//    Z (1 - exp(-H / Z)) (1.77 km continental, 1.90 km desert, 0.86 km maritime), surface
//    extinction beta_550 = tau_550 / that, OPAC's small free-tropospheric and stratospheric
//    parts folded in so that the column keeps the type's tau_550. (The layer's sharp top
//    itself would cost the fast methods' few steps along a ray more than its shape is
//    worth to the sky's look.) The phase function is Henyey-Greenstein with OPAC's asymmetry parameter (its
//    first Legendre moment is g, as the asymmetry parameter's definition asks).
//  * Sun: ASTM G-173 extraterrestrial spectrum; angular radius 0.004675 rad.
#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include <fmt/format.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"
#include "welkin/color/spectral_data.hpp"

namespace welkin {
namespace {

constexpr double kEarthRadius = 6360e3, kEarthTop = 6420e3;
constexpr double kRayleighAt1um = 1.24062e-6;  // m^-1

double rayleigh_earth(double lambda_nm) { return kRayleighAt1um * std::pow(lambda_nm / 1000.0, -4.0); }

double ozone_earth(double lambda_nm, double dobson_units) {
    const double tent_integral_m = 15e3;
    const double peak_number_density = dobson_units * kDobsonUnit / tent_integral_m;  // m^-3
    return peak_number_density * ozone_cross_section_m2(lambda_nm);
}

struct Aerosol {
    double extinction_550;  // m^-1 at the surface
    double angstrom_alpha;
    std::function<double(double)> albedo;  // single-scattering albedo vs wavelength
    double scale_height_m;
    double g;
    MiePhaseModel phase = MiePhaseModel::CornetteShanks;
};

Atmosphere earth(const std::string& name, const std::vector<double>& w, const Aerosol& aerosol,
                 const std::function<double(double)>& ground_albedo) {
    Atmosphere a;
    a.name = name;
    a.wavelengths_nm = w;
    a.bottom_radius_m = kEarthRadius;
    a.top_radius_m = kEarthTop;
    a.sun_angular_radius_rad = 0.004675;
    a.rayleigh_density = DensityProfile::exponential(8000.0);
    a.mie_density = DensityProfile::exponential(aerosol.scale_height_m);
    a.absorption_density = DensityProfile::tent(10e3, 25e3, 40e3);
    a.mie_phase = aerosol.phase;
    a.mie_g = aerosol.g;
    for (double l : w) {
        a.solar_irradiance.push_back(solar_irradiance_astm_g173(l));
        a.rayleigh_scattering.push_back(rayleigh_earth(l));
        const double ext = aerosol.extinction_550 * std::pow(l / 550.0, -aerosol.angstrom_alpha);
        a.mie_extinction.push_back(ext);
        a.mie_scattering.push_back(ext * aerosol.albedo(l));
        a.absorption_extinction.push_back(ozone_earth(l, 300.0));
        a.ground_albedo.push_back(ground_albedo(l));
    }
    return a;
}

// Linear interpolation through (lambda, value) knots, clamped at the ends.
std::function<double(double)> knots(std::vector<std::pair<double, double>> k) {
    return [k](double l) {
        if (l <= k.front().first) return k.front().second;
        for (std::size_t i = 1; i < k.size(); ++i)
            if (l <= k[i].first) {
                const double f = (l - k[i - 1].first) / (k[i].first - k[i - 1].first);
                return k[i - 1].second * (1 - f) + k[i].second * f;
            }
        return k.back().second;
    };
}

// An OPAC aerosol type (header): tau_550, omega, g, the Angstrom exponents below and
// above 500 nm, and the profile (scale height Z through a mixing layer of height H).
struct OpacType {
    double tau_550, omega, g, alpha_blue, alpha_red, scale_height_m, mixing_layer_m;
};

// Continental clean, average and polluted, urban, desert, maritime clean (Table 4).
constexpr OpacType kContinentalClean{0.064, 0.972, 0.709, 1.10, 1.42, 8000.0, 2000.0};
constexpr OpacType kContinentalAverage{0.151, 0.925, 0.703, 1.11, 1.42, 8000.0, 2000.0};
constexpr OpacType kContinentalPolluted{0.327, 0.892, 0.698, 1.13, 1.45, 8000.0, 2000.0};
constexpr OpacType kUrban{0.643, 0.817, 0.689, 1.14, 1.43, 8000.0, 2000.0};
constexpr OpacType kDesert{0.286, 0.888, 0.729, 0.20, 0.17, 2000.0, 6000.0};
constexpr OpacType kMaritimeClean{0.096, 0.998, 0.772, 0.12, 0.08, 1000.0, 2000.0};

// The Earth with an OPAC aerosol type whose optical depth at 550 nm is `tau_550` (the
// type's own, or a climatology's for the same type).
Atmosphere earth_opac(const std::string& name, const std::vector<double>& w, const OpacType& t,
                      double tau_550, const std::function<double(double)>& ground_albedo) {
    // OPAC's column per unit surface extinction, Z (1 - exp(-H / Z)), as the scale height
    // of one exponential (header).
    const double column_m = t.scale_height_m * (1.0 - std::exp(-t.mixing_layer_m / t.scale_height_m));
    const double beta_550 = tau_550 / column_m;  // m^-1 at the ground
    Atmosphere a = earth(name, w,
                         Aerosol{beta_550, 0.0, [&](double) { return t.omega; }, column_m, t.g,
                                 MiePhaseModel::HenyeyGreenstein},
                         ground_albedo);
    for (std::size_t c = 0; c < w.size(); ++c) {
        // Angstrom's law in two pieces, continuous at 500 nm.
        const double l = w[c];
        const double f = l >= 500.0
                             ? std::pow(l / 550.0, -t.alpha_red)
                             : std::pow(500.0 / 550.0, -t.alpha_red) * std::pow(l / 500.0, -t.alpha_blue);
        a.mie_extinction[c] = beta_550 * f;
        a.mie_scattering[c] = beta_550 * f * t.omega;
    }
    return a;
}

// Bruneton 2017's demo atmosphere (the peer data's; see tests/data/README.md):
// Mie extinction 5.328e-3 / 1200 m at every wavelength, albedo 0.9, g = 0.8
// Cornette-Shanks, ground albedo 0.1.
Atmosphere bruneton2017(const std::vector<double>& w) {
    return earth("bruneton2017", w, Aerosol{5.328e-3 / 1200.0, 0.0, [](double) { return 0.9; }, 1200.0, 0.8},
                 [](double) { return 0.1; });
}

// Ground albedos (Lambertian) through the visible, rounded readings of the USGS Spectral Library
// (Kokaly et al. 2017, "USGS Spectral Library Version 7", Data Series 1035): green
// vegetation (lawn grass: dark in the blue and red, the green peak at 550 nm), desert sand;
// open sea 0.06 (Payne 1972, "Albedo of the sea surface", J. Atmos. Sci. 29, sun above
// 30 degrees); a city's 0.12 grey (Taha 1997, "Urban climates and heat islands", Energy
// and Buildings 25: 0.10-0.20).
std::function<double(double)> vegetation() {
    return knots({{400, 0.04},
                  {450, 0.05},
                  {500, 0.07},
                  {550, 0.11},
                  {600, 0.07},
                  {650, 0.05},
                  {690, 0.07},
                  {720, 0.25},
                  {760, 0.45}});
}
std::function<double(double)> sand() {
    return knots({{400, 0.20}, {450, 0.25}, {550, 0.34}, {650, 0.42}, {750, 0.47}});
}
std::function<double(double)> grey(double albedo) {
    return [albedo](double) { return albedo; };
}

// The weather an artist picks, each an OPAC type (header) over a ground albedo.
// Very clear air ("clear"): continental clean, tau_550 = 0.064; green vegetation.
Atmosphere clear(const std::vector<double>& w) {
    return earth_opac("clear", w, kContinentalClean, kContinentalClean.tau_550, vegetation());
}

// An ordinary clear day (the default): continental average aerosol with the global mean
// optical depth of the aerosol climatologies, tau_550 = 0.12 (Kinne et al. 2013, "MAC-v1:
// A new global aerosol climatology for climate studies", JAMES 5, 704-740: 0.12 annual
// global mean at 550 nm); green vegetation.
Atmosphere clear_day(const std::vector<double>& w) {
    return earth_opac("clear_day", w, kContinentalAverage, 0.12, vegetation());
}

// Hazy: continental polluted, tau_550 = 0.327; green vegetation.
Atmosphere hazy(const std::vector<double>& w) {
    return earth_opac("hazy", w, kContinentalPolluted, kContinentalPolluted.tau_550, vegetation());
}

// Polluted: urban, tau_550 = 0.643, absorbing soot (omega 0.817); a city's grey.
Atmosphere polluted(const std::vector<double>& w) {
    return earth_opac("polluted", w, kUrban, kUrban.tau_550, grey(0.12));
}

// Desert dust: desert, tau_550 = 0.286, nearly grey extinction; sand.
Atmosphere desert_dust(const std::vector<double>& w) {
    return earth_opac("desert_dust", w, kDesert, kDesert.tau_550, sand());
}

// Maritime: maritime clean, tau_550 = 0.096, sea salt (omega 0.998); open sea.
Atmosphere maritime(const std::vector<double>& w) {
    return earth_opac("maritime", w, kMaritimeClean, kMaritimeClean.tau_550, grey(0.06));
}

// Mars, at 1.524 AU (solar irradiance / 1.524^2, angular radius / 1.524).
//  * Radius 3389.5 km (NASA Mars fact sheet); atmosphere top at 80 km.
//  * CO2 Rayleigh scattering: surface number density 610 Pa / (k 210 K) = 2.10e23 m^-3,
//    0.826 % of Earth's sea-level 2.547e25 m^-3, with a CO2 / air cross-section ratio of
//    2.45 (Sneep & Ubachs 2005, JQSRT 92); scale height 11.1 km.
//  * Dust: visible optical depth 0.5 over an 11.1 km scale height (a clear season), grey
//    extinction (effective radius ~1.5 um), single-scattering albedo rising from 0.65 in
//    the near-UV to 0.97 in the red and asymmetry g = 0.63 (Wolff et al. 2009, JGR 114,
//    E00D04): this is what makes the day sky butterscotch and the sunset blue.
//  * No ozone to speak of; ochre ground albedo 0.1 (blue) to 0.3 (red).
Atmosphere mars(const std::vector<double>& w) {
    constexpr double kDistanceAu = 1.524;
    constexpr double kScaleHeight = 11.1e3;
    const double rayleigh_scale = 2.104e23 / 2.547e25 * 2.45;
    const auto dust_albedo = knots({{360, 0.65}, {440, 0.75}, {550, 0.90}, {680, 0.97}, {830, 0.98}});
    const auto ground = knots({{440, 0.10}, {550, 0.18}, {680, 0.30}});
    Atmosphere a;
    a.name = "mars";
    a.wavelengths_nm = w;
    a.bottom_radius_m = 3389.5e3;
    a.top_radius_m = 3389.5e3 + 80e3;
    a.sun_angular_radius_rad = 0.004675 / kDistanceAu;
    a.rayleigh_density = DensityProfile::exponential(kScaleHeight);
    a.mie_density = DensityProfile::exponential(kScaleHeight);
    a.absorption_density = DensityProfile::zero();
    a.mie_phase = MiePhaseModel::HenyeyGreenstein;
    a.mie_g = 0.63;
    const double dust_extinction = 0.5 / kScaleHeight;
    for (double l : w) {
        a.solar_irradiance.push_back(solar_irradiance_astm_g173(l) / (kDistanceAu * kDistanceAu));
        a.rayleigh_scattering.push_back(rayleigh_earth(l) * rayleigh_scale);
        a.mie_extinction.push_back(dust_extinction);
        a.mie_scattering.push_back(dust_extinction * dust_albedo(l));
        a.absorption_extinction.push_back(0.0);
        a.ground_albedo.push_back(ground(l));
    }
    return a;
}

using PresetFactory = Atmosphere (*)(const std::vector<double>&);
// In the order offered: the default first, then by the weather, then the validation and
// the other planet.
const std::vector<std::pair<std::string, PresetFactory>>& presets() {
    static const std::vector<std::pair<std::string, PresetFactory>> p{{"clear_day", clear_day},
                                                                      {"clear", clear},
                                                                      {"hazy", hazy},
                                                                      {"polluted", polluted},
                                                                      {"desert_dust", desert_dust},
                                                                      {"maritime", maritime},
                                                                      {"bruneton2017", bruneton2017},
                                                                      {"mars", mars}};
    return p;
}

}  // namespace

std::vector<std::string> Atmosphere::preset_names() {
    std::vector<std::string> names;
    for (const auto& [name, _] : presets()) names.push_back(name);
    return names;
}

Atmosphere Atmosphere::preset(const std::string& name, const std::vector<double>& wavelengths_nm) {
    const auto it =
        std::find_if(presets().begin(), presets().end(), [&](const auto& p) { return p.first == name; });
    if (it == presets().end())
        throw InvalidArgument("preset", fmt::format("unknown preset '{}'; choose one of: {}", name,
                                                    fmt::join(preset_names(), ", ")));
    const std::vector<double>& w = wavelengths_nm.empty() ? default_wavelengths_nm() : wavelengths_nm;
    for (std::size_t i = 0; i < w.size(); ++i)
        require_in_range(fmt::format("wavelengths_nm[{}]", i), w[i], 360.0, 830.0, "nm");
    Atmosphere a = it->second(w);
    a.validate();
    return a;
}

}  // namespace welkin
