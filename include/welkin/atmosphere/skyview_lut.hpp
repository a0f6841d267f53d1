// SPDX-License-Identifier: Apache-2.0
// Sky-view LUT (Hillaire 2020 sec. 5.3, 192 x 108 texels): the path radiance around one
// observer for one sun position, parametrised by the view's zenith angle and its azimuth
// relative to the sun.
//
// Latitude: the horizon sits at zenith angle theta_h = pi - beta, cos(beta) = rho / r
// (rho = sqrt(r^2 - R^2)). Hillaire's non-linear mapping spends texels near it:
//   above the horizon (v < 1/2):  theta = theta_h (1 - (1 - s)^2), s = 2v at the texels'
//                                  edges; the h/2 rows sit evenly in s from the zenith
//                                  (row 0: s = 0, the zenith itself) to just above the
//                                  horizon (s = 1 - 1/h), so that the pole is a row
//   below the horizon (v > 1/2):  theta = theta_h + beta (2v - 1)^2
// and, since the sky just above the horizon and the ground just below it differ by orders
// of magnitude, a lookup never interpolates across v = 1/2 (the height must be even).
// Longitude: azimuth phi from the sun in [0, pi] (the sky is symmetric about the sun's
// vertical plane), u = sin(phi / 2) = sqrt((1 - cos phi) / 2), which packs texels around
// the sun where the Mie peak is.
//
// The LUT is only valid for an observer inside the atmosphere; LutSky falls back to the
// ray-march for observers above the top (Hillaire 2020 sec. 5.3 moves such a camera to the
// top of the atmosphere, which is only right for views straight down).
#pragma once

#include <span>

#include <glm/vec3.hpp>

#include "welkin/atmosphere/multiscattering_lut.hpp"

namespace welkin {

class SkyViewLut {
public:
    SkyViewLut(const AtmosphereBatch& batch, const TransmittanceLut& transmittance,
               const MultiScatteringLut& multiscattering, double r, double mu_s, int width, int height,
               int steps = 30);

    // Path radiance for a view with zenith cosine mu and azimuth cosine cos_phi relative
    // to the sun.
    Spectrum4 radiance(double mu, double cos_phi) const;

    // radiance() for many views at once: `directions` (finite non-zero vectors, normalised
    // here; Z up) around the sun `sun` (a unit vector), with mu and cos_phi as
    // view_geometry() gives them. Writes lanes [0, count) of each view's radiance to
    // out[i * stride + c]. The same values as one call per view, computed in blocks: a
    // pass over the block for the texel coordinates (the angles, the acos and the latitude
    // mapping: arithmetic only, it vectorises), then the bilinear fetches. A LUT whose
    // texels are all 0 (no light: the sun far below the horizon) writes 0 at once.
    void radiance(std::span<const glm::dvec3> directions, const glm::dvec3& sun, std::size_t count,
                  float* out, std::size_t stride) const;

    const Texture2D& texture() const { return texture_; }

    // The view's zenith angle, acos(mu) to 1e-8 rad, in a form that vectorises (both
    // radiance() forms map it to the texture's v by Hillaire's latitude mapping, above).
    static double zenith_angle(double mu);

private:
    double r_, theta_h_, beta_;
    Texture2D texture_;
    bool dark_ = false;  // every texel 0
};

}  // namespace welkin
