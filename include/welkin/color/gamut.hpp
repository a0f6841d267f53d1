// SPDX-License-Identifier: Apache-2.0
// Bringing an RGB colour that lies outside its space's gamut back into it.
//
// A spectrum -> RGB conversion (color.hpp) is linear; where a spectrum's chromaticity lies
// outside the triangle of the output primaries (the deep blue of a twilight zenith, the
// red of a sun near the horizon, or the fitted four-wavelength matrices' small errors), one
// channel comes out negative. A renderer takes negative radiance as light taken away, so
// every RGB this engine outputs goes through gamut_map() right after the conversion.
//
// Method: desaturation toward the white point at constant luminance. With Y = w . rgb the
// luminance (w: the Y row of the space's RGB -> XYZ matrix, summing to 1, so that
// (1, 1, 1) is the space's white),
//     rgb' = Y + s (rgb - Y),   s = Y / (Y - min(r, g, b))   when min(r, g, b) < 0 < Y,
// i.e. the additive mixture of the colour with the just sufficient amount of white of the
// same luminance. It keeps
//  * the luminance Y exactly (w . (rgb - Y) = 0);
//  * the hue: in the chromaticity diagram the mixture lies on the straight line from the
//    white point through the colour, which is the line of constant dominant wavelength
//    (CIE 15:2004, Colorimetry, 3rd ed., sec. 9.1, dominant wavelength and purity);
//  * the least loss of saturation that reaches the gamut (the first channel reaches 0);
// and leaves in-gamut colours untouched. It is the constant-lightness, hue-preserving
// clipping toward the neutral axis ("straight" or "centre" clipping) of the gamut-mapping
// literature (Morovic & Luo 2001, "The fundamentals of gamut mapping: a survey",
// J. Imaging Sci. Technol. 45(3), 283-290; Morovic 2008, "Color Gamut Mapping", Wiley,
// ch. 10), done in linear light so that no luminance is created or lost. There is no upper
// bound: scene-linear radiance has none. A colour whose luminance is not positive has no
// in-gamut colour of its luminance; it maps to black (0, 0, 0). A non-finite input is
// returned as it is, for the callers' own checks to report.
#pragma once

#include <array>

namespace welkin {

// The Y row of an RGB -> XYZ matrix (row-major 3 x 3): a space's luminance weights.
constexpr std::array<double, 3> luminance_weights(const std::array<double, 9>& rgb_to_xyz) {
    return {rgb_to_xyz[3], rgb_to_xyz[4], rgb_to_xyz[5]};
}

std::array<double, 3> gamut_map(const std::array<double, 3>& rgb,
                                const std::array<double, 3>& luminance_weights);

// In place on `count` packed triples (float, as the images hold them).
void gamut_map(float* rgb, std::size_t count, const std::array<double, 3>& luminance_weights);

}  // namespace welkin
