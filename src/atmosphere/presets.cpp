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
//  * Aerosol (Mie): beta_M(lambda) = beta_550 (lambda / 550 nm)^-alpha (Angstrom 1929),
//    with single-scattering albedo omega. The presets differ by the aerosol's surface
//    extinction, chosen from a meteorological visibility V by Koschmieder's relation
//    V = 3.912 / beta_ext(550 nm) (Koschmieder 1924), its scale height, alpha, omega and
//    asymmetry g, taken from the OPAC aerosol types (Hess, Koepke & Schult 1998,
//    "Optical Properties of Aerosols and Clouds: The Software Package OPAC", BAMS 79).
//  * Sun: ASTM G-173 extraterrestrial spectrum; angular radius 0.004675 rad.
#include <cmath>
#include <functional>
#include <map>

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
                 double ground_albedo) {
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
        a.ground_albedo.push_back(ground_albedo);
    }
    return a;
}

double koschmieder_aerosol_extinction(double visibility_m, double lambda_nm = 550.0) {
    // Total extinction 3.912 / V at the surface, less the Rayleigh part.
    return std::max(0.0, 3.912 / visibility_m - rayleigh_earth(lambda_nm));
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

// Bruneton 2017's demo atmosphere (the peer data's; see tests/data/README.md):
// Mie extinction 5.328e-3 / 1200 m at every wavelength, albedo 0.9, g = 0.8
// Cornette-Shanks, ground albedo 0.1.
Atmosphere bruneton2017(const std::vector<double>& w) {
    return earth("bruneton2017", w, Aerosol{5.328e-3 / 1200.0, 0.0, [](double) { return 0.9; }, 1200.0, 0.8},
                 0.1);
}

// Clear: clean continental aerosol (OPAC), visibility 150 km, alpha 1.1, omega 0.97,
// g 0.7, scale height 1.2 km; green-vegetation ground albedo 0.15.
Atmosphere clear(const std::vector<double>& w) {
    return earth(
        "clear", w,
        Aerosol{koschmieder_aerosol_extinction(150e3), 1.1, [](double) { return 0.97; }, 1200.0, 0.7}, 0.15);
}

// Hazy: continental average aerosol (OPAC), visibility 20 km, alpha 1.3, omega 0.93,
// g 0.71, deeper mixing layer (scale height 2 km); ground albedo 0.15.
Atmosphere hazy(const std::vector<double>& w) {
    return earth(
        "hazy", w,
        Aerosol{koschmieder_aerosol_extinction(20e3), 1.3, [](double) { return 0.93; }, 2000.0, 0.71}, 0.15);
}

// Polluted: urban aerosol (OPAC), visibility 8 km, alpha 1.4, absorbing soot (omega 0.82),
// g 0.69, shallow boundary layer (scale height 1.2 km); urban ground albedo 0.12.
Atmosphere polluted(const std::vector<double>& w) {
    return earth("polluted", w,
                 Aerosol{koschmieder_aerosol_extinction(8e3), 1.4, [](double) { return 0.82; }, 1200.0, 0.69},
                 0.12);
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
const std::map<std::string, PresetFactory>& presets() {
    static const std::map<std::string, PresetFactory> p{{"bruneton2017", bruneton2017},
                                                        {"clear", clear},
                                                        {"hazy", hazy},
                                                        {"polluted", polluted},
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
    const auto it = presets().find(name);
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
