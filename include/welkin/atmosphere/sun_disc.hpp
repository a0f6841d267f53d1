// SPDX-License-Identifier: Apache-2.0
// The sun's disc as a radiance distribution: the one model that every renderer of the disc
// uses (the equirectangular sky image, the camera plate, the add-on's shader nodes through
// the Python binding).
//
// The disc is a cap of angular radius alpha = atmosphere.sun_angular_radius_rad around the
// sun direction. Along a ray at angle rho < alpha from its centre, above the horizon, its
// spectral radiance is
//     L(rho, lambda) = L_mean(lambda) * LD(rho, lambda),
//     L_mean(lambda) = E_dir(lambda) / (f_vis * Omega_sun),  Omega_sun = 2 pi (1 - cos alpha),
// with E_dir the direct irradiance of sun_radiometry() (solar irradiance x transmittance x
// the visible fraction f_vis of the disc) and LD the limb-darkening factor of sun.hpp
// (Neckel & Labs 1994, normalised to a mean of 1 over the disc's solid angle). So the
// integral of L over the visible part of the disc is E_dir (to the flatness of the horizon
// chord across 0.5 degrees): the energy of the disc is the direct irradiance.
//
// Limb darkening as a polynomial. Neckel & Labs write the centre-to-limb variation as
// I(mu) / I(1) = sum_k a_k mu^k with mu = cos(heliocentric angle) = sqrt(1 - s^2),
// s = sin rho / sin alpha; the profile is positive and falls from 1 at the centre to the
// limb for every wavelength, though the a_k alternate in sign. The RGB disc is
//     L_rgb,j(mu) = L_centre,rgb,j sum_k b_jk mu^k,   b_jk = sum_c w_jc a_k,c,
// a convex combination of the per-wavelength profiles (w_jc >= 0, summing to 1), so each
// channel's profile is again a physical one: positive, 1 at the centre, darkening to the
// limb. The weights are w_jc ~ max(0, M_jc L_centre,c), with M the 3 x C sunlight matrix
// (color.hpp): where M's entries are positive this is the exact linear map of the
// spectral disc (b_jk = sum_c M_jc L_centre,c a_k,c / sum_c M_jc L_centre,c); a fitted
// matrix's negative entries would otherwise make b_jk the ratio of two small numbers of
// either sign. L_centre,rgb is set so that the disc's mean radiance is
// gamut_map(M L_mean) (gamut.hpp): the disc integrates to the lamp's colour and is
// never negative. A shader that evaluates this polynomial per RGB channel reproduces the
// core's disc.
#pragma once

#include <array>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/observer.hpp"
#include "welkin/atmosphere/sun.hpp"

namespace welkin {

class SunDisc {
public:
    SunDisc(const Atmosphere& atmosphere, const Observer& observer);

    double angular_radius_rad() const { return alpha_; }
    double solid_angle_sr() const { return omega_; }
    const glm::dvec3& direction() const { return direction_; }
    const SunRadiometry& radiometry() const { return sun_; }
    std::size_t channels() const { return mean_.size(); }
    // Per channel, W m^-2 sr^-1 nm^-1; 0 when the whole disc is below the horizon.
    const std::vector<double>& mean_radiance() const { return mean_; }
    std::vector<double> centre_radiance() const;
    // Neckel & Labs' a_0..a_5 per channel (summing to 1): L = L_centre sum_k a_k mu^k.
    const std::vector<std::array<double, 6>>& limb_coefficients() const { return coefficients_; }

    // The disc in linear RGB (W m^-2 sr^-1) as L_centre_rgb[j] sum_k b[j][k] mu^k
    // (header), with `to_rgb` the 3 x C sunlight matrix (SpectrumToRgb(wl, 0).matrix())
    // and `luminance` the same space's luminance weights (its luminance_weights()).
    struct Rgb {
        std::array<double, 3> centre_radiance{};
        std::array<std::array<double, 6>, 3> limb_coefficients{};
    };
    Rgb rgb(std::span<const double> to_rgb, const std::array<double, 3>& luminance) const;

    // Angle from the disc centre; the radiance of channel c there (0 outside the disc).
    // Whether the ray is above the horizon is the caller's test (it knows the ray's origin).
    double angle_to(const glm::dvec3& unit_direction) const;
    double radiance(std::size_t channel, double angle_rad) const {
        return mean_[channel] * limb_[channel](angle_rad);
    }
    // All channels at once into `out` (size channels()), scaled by `weight` and added.
    // Returns false (adding nothing) outside the disc.
    bool add_radiance(double angle_rad, double weight, std::span<double> out) const;

private:
    double alpha_, omega_;
    glm::dvec3 direction_;
    SunRadiometry sun_;
    std::vector<LimbDarkening> limb_;
    std::vector<std::array<double, 6>> coefficients_;
    std::vector<double> mean_;
};

}  // namespace welkin
