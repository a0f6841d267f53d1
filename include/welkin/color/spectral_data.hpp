// SPDX-License-Identifier: Apache-2.0
// Measured spectra the presets and the colour conversion are built from.
//
// Both tables are sampled in 10 nm bins from 360 to 830 nm and interpolated linearly
// (clamped to the end values outside that range).
#pragma once

namespace welkin {

// Extraterrestrial solar spectral irradiance, W m^-2 nm^-1: ASTM G-173-03 reference
// spectrum (extraterrestrial column), averaged per 10 nm bin; the same table as
// tests/data/solar_irradiance_astm_g173_10nm.csv, extended to 830 nm.
double solar_irradiance_astm_g173(double wavelength_nm);

// Ozone absorption cross-section, m^2 per molecule, at 233 K: Serdyuchenko et al. 2014,
// "High spectral resolution ozone absorption cross-sections", Atmos. Meas. Tech. 7,
// 625-636 (IUP Bremen reference spectra 2011), averaged per 10 nm bin.
double ozone_cross_section_m2(double wavelength_nm);

// One Dobson unit, molecules per m^2.
inline constexpr double kDobsonUnit = 2.687e20;

}  // namespace welkin
