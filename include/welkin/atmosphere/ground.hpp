// SPDX-License-Identifier: Apache-2.0
// The planet's surface below the horizon: a Lambertian ground lit by the sun through the
// air and by the sky, seen through the air in front of it.
//
// Model (Bruneton 2017, "Precomputed Atmospheric Scattering: a New Implementation",
// functions.glsl GetSkyRadianceToPoint / ComputeDirectIrradiance /
// ComputeIndirectIrradiance, and Bruneton & Neyret 2008 sec. 4): a ray from the observer
// x that meets the ground at p sees
//     L = L_path(x -> p) + T(x -> p) * (albedo / pi) * (E_sun(p) + E_sky(p)),
// with L_path the air's in-scattered radiance along the segment (what every sky method
// returns for a view that meets the ground), T its transmittance, and the irradiance of
// the horizontal surface at p
//     E_sun(p) = E_0 * T(p -> sun) * f_vis * max(mu_s, 0)   (direct, sun.hpp's radiometry
//                                                           at p: f_vis the visible disc)
//     E_sky(p) = integral over the upper hemisphere of L_sky(p, w) (n . w) dw,
// mu_s the cosine of the sun's zenith angle at p. Both depend on p through mu_s only (the
// ground is a sphere and the air is spherically layered), so they are tabulated once per
// atmosphere over mu_s. E_sky integrates the sky-view LUT (skyview_lut.hpp: Hillaire
// 2020's sky with multiple scattering) at the ground for each tabulated sun, on a product
// rule over the hemisphere: Gauss-Legendre in mu = cos(zenith) (the integrand L mu dmu
// dphi) and the midpoint rule in azimuth, whose halves are mirror images about the sun's
// vertical plane. Light the ground sends back up into the sky, and on to the ground again,
// is left out (Bruneton's ground-albedo orders; a few percent of E_sky for albedo 0.3).
//
// With no air (T = 1, L_path = 0, E_sky = 0) the ground's radiance is the closed form
// albedo / pi * E_0 * mu_s (tests/cpp/test_ground.cpp).
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "welkin/atmosphere/atmosphere.hpp"

namespace welkin {

class GroundIllumination {
public:
    // Tables over mu_s for `atmosphere` (its LUTs from the shared cache, Hillaire's
    // default sizes).
    explicit GroundIllumination(const Atmosphere& atmosphere);

    std::size_t channels() const { return channels_; }
    // Irradiance of the horizontal ground (sun + sky), W m^-2 nm^-1 per channel, for the
    // sun's zenith cosine mu_s at the ground point; linear in mu_s between table entries.
    void irradiance(double mu_s, std::span<double> out) const;
    void sun_irradiance(double mu_s, std::span<double> out) const;
    void sky_irradiance(double mu_s, std::span<double> out) const;

    // The tables for `atmosphere` from a small process-wide cache (the two most recently
    // used atmospheres, each kept as an exact copy, never a hash, as AtmosphereLutCache
    // does): they depend on the atmosphere alone, so a sun change reuses them. Building is
    // deterministic, so cached and fresh tables are identical. Thread-safe; the lock is not
    // held while building.
    static std::shared_ptr<const GroundIllumination> shared(const Atmosphere& atmosphere);

    static constexpr int kTableSize = 48;     // mu_s in [kMinMuS, 1]
    static constexpr double kMinMuS = -0.35;  // 20.5 degrees below the horizon

private:
    struct Entry {
        std::size_t first;  // of table row i, the lower of the two mu_s entries around mu_s
        double fraction;    // the weight of row i + 1
    };
    Entry entry(double mu_s) const;
    void lookup(const std::vector<double>& table, double mu_s, std::span<double> out) const;
    std::size_t channels_;
    std::vector<double> sun_, sky_;  // (kTableSize, channels)
};

// Transmittance of every channel along the ray from radius r with zenith cosine mu over
// [0, length_m] (optical_depth.hpp's quadrature).
std::vector<double> transmittance_along(const Atmosphere& atmosphere, double r, double mu, double length_m);

}  // namespace welkin
