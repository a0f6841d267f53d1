// SPDX-License-Identifier: Apache-2.0
// A reflectance spectrum for an RGB colour: what an artist's colour picker gives, as the
// spectral albedo the atmosphere's ground needs.
//
// Method: Jakob & Hanika 2019, "A Low-Dimensional Function Space for Efficient Spectral
// Upsampling" (Computer Graphics Forum 38(2), Eurographics), eq. (3)-(4): the spectrum is
// a sigmoid of a quadratic,
//     R(lambda) = S(c0 t^2 + c1 t + c2),   S(x) = 1/2 + x / (2 sqrt(1 + x^2)),
// (t = (lambda - 360 nm) / 470 nm, the quadratic's argument scaled to [0, 1]), smooth and
// strictly inside (0, 1) for every c, so a physically valid albedo whatever is fitted. The
// three coefficients are fitted (Gauss-Newton with Levenberg's damping, as the paper's
// optimisation) so that the spectrum's colour equals the asked one. A reflectance's colour
// needs a light: here the spectrum's colour is that of light reflected from it relative to
// light from a perfect white reflector (R = 1), each channel of the space's RGB (CIE 1931
// XYZ, color.hpp, through the space's matrix) divided by the white's, so that
//  * a grey (r = g = b) is the flat spectrum of that value exactly (and black and white,
//    which the sigmoid reaches only in the limit, are 0 and 1 at every wavelength);
//  * a colour keeps its chromaticity under any light whose spectrum is smooth, sunlight
//    and skylight included, to the accuracy of that approximation (tests/cpp/test_reflectance.cpp,
//    tests/python/test_ground_colour.py).
// A saturated colour no reflectance in [0, 1] has (outside the object-colour solid; a
// Rec.709 primary at full value is near its edge) gets the closest sigmoid spectrum in RGB
// (least squares): the hue kept, the saturation as high as a reflectance allows.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "welkin/color/color_space.hpp"

namespace welkin {

// The reflectance spectrum (every value in [0, 1]) at `wavelengths_nm` whose colour
// (header) in `space` is `rgb` (linear, each channel in [0, 1]). Throws InvalidArgument
// naming `parameter` ("ground_color" by default) for a channel outside [0, 1] or not
// finite, and naming "wavelengths_nm" for an empty or non-finite wavelength list.
std::vector<double> rgb_to_reflectance(const std::array<double, 3>& rgb,
                                       std::span<const double> wavelengths_nm,
                                       ColorSpace space = ColorSpace::Rec709,
                                       const char* parameter = "ground_color");

// The colour of a reflectance spectrum sampled at `wavelengths_nm` (linearly interpolated,
// constant beyond the ends) as defined in the header: relative to a perfect white
// reflector in `space`. The inverse of rgb_to_reflectance for colours a reflectance has.
std::array<double, 3> reflectance_to_rgb(std::span<const double> reflectance,
                                         std::span<const double> wavelengths_nm,
                                         ColorSpace space = ColorSpace::Rec709);

}  // namespace welkin
