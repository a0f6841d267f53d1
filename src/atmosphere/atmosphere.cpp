// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/atmosphere.hpp"

#include <cmath>

#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {

const std::vector<double>& default_wavelengths_nm() {
    static const std::vector<double> w{620.0, 560.0, 480.0, 440.0};
    return w;
}

std::vector<double> spectral_wavelengths_nm(double step_nm) {
    require_in_range("step_nm", step_nm, 1.0, 235.0, "nm");
    std::vector<double> w;
    for (double l = 360.0; l <= 830.0 + 1e-9; l += step_nm) w.push_back(l);
    return w;
}

namespace {

void require_spectrum(const std::string& parameter, const std::vector<double>& v, std::size_t channels,
                      double lo, double hi, const std::string& unit) {
    if (v.size() != channels)
        throw InvalidArgument(parameter,
                              fmt::format("needs one value per wavelength ({}), got {}", channels, v.size()));
    for (std::size_t i = 0; i < v.size(); ++i)
        require_in_range(fmt::format("{}[{}]", parameter, i), v[i], lo, hi, unit);
}

}  // namespace

void Atmosphere::validate() const {
    const std::size_t n = wavelengths_nm.size();
    if (n == 0 || n > 1024)
        throw InvalidArgument("wavelengths_nm", fmt::format("needs 1 to 1024 wavelengths, got {}", n));
    require_spectrum("wavelengths_nm", wavelengths_nm, n, 200.0, 3000.0, "nm");
    require_spectrum("solar_irradiance", solar_irradiance, n, 0.0, 1e4, "W m^-2 nm^-1");
    require_in_range("sun_angular_radius_rad", sun_angular_radius_rad, 1e-5, 0.2, "rad");

    require_in_range("bottom_radius_m", bottom_radius_m, 1e3, 1e9, "m");
    if (!(top_radius_m > bottom_radius_m) || !std::isfinite(top_radius_m))
        throw InvalidArgument("top_radius_m",
                              fmt::format("must be finite and greater than bottom_radius_m ({} m), got {} m",
                                          bottom_radius_m, top_radius_m));
    require_in_range("top_radius_m - bottom_radius_m", top_radius_m - bottom_radius_m, 1.0,
                     0.5 * bottom_radius_m, "m");

    // Coefficients up to 1 m^-1: a mean free path of a metre is already a dense fog.
    rayleigh_density.validate("rayleigh.density");
    require_spectrum("rayleigh.scattering", rayleigh_scattering, n, 0.0, 1.0, "m^-1");
    mie_density.validate("mie.density");
    require_spectrum("mie.scattering", mie_scattering, n, 0.0, 1.0, "m^-1");
    require_spectrum("mie.extinction", mie_extinction, n, 0.0, 1.0, "m^-1");
    for (std::size_t i = 0; i < n; ++i)
        if (mie_scattering[i] > mie_extinction[i] * (1.0 + 1e-12))
            throw InvalidArgument(fmt::format("mie.scattering[{}]", i),
                                  fmt::format("must be in [0, mie.extinction[{}] = {}] m^-1, got {}", i,
                                              mie_extinction[i], mie_scattering[i]));
    // |g| = 1 is a delta function; 0.999 is the strongest peak the methods are charted at.
    require_in_range("mie.g", mie_g, -0.999, 0.999);
    absorption_density.validate("absorption.density");
    require_spectrum("absorption.extinction", absorption_extinction, n, 0.0, 1.0, "m^-1");
    require_spectrum("ground_albedo", ground_albedo, n, 0.0, 1.0, "");
}

double Atmosphere::extinction(std::size_t c, double h) const {
    return rayleigh_scattering[c] * rayleigh_density.density(h) + mie_extinction[c] * mie_density.density(h) +
           absorption_extinction[c] * absorption_density.density(h);
}

double Atmosphere::scattering(std::size_t c, double h) const {
    return rayleigh_scattering[c] * rayleigh_density.density(h) + mie_scattering[c] * mie_density.density(h);
}

}  // namespace welkin
