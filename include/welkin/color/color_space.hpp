// SPDX-License-Identifier: Apache-2.0
// The linear RGB spaces Welkin writes colour in, and the matrices from CIE XYZ to them.
//
// Every colour starts as a spectrum, becomes CIE 1931 XYZ (color.hpp) and then the RGB of
// one of these spaces through xyz_to_rgb_matrix. XYZ here is the spectrum's own, with
// the D65 white of Rec.709 and Rec.2020 (equal RGB = white, as in Blender's configuration
// and Bruneton 2017's XYZ_TO_SRGB):
//  * Rec709: linear sRGB / ITU-R BT.709 primaries, D65. The IEC 61966-2-1 matrix to four
//    decimals, as Bruneton 2017 (atmosphere/constants.h) and the data of tests/data use.
//  * Rec2020: ITU-R BT.2020-2 (Table 3) primaries R (0.708, 0.292), G (0.170, 0.797),
//    B (0.131, 0.046), white D65 (0.3127, 0.3290); the matrix is the normalised primary
//    matrix of SMPTE RP 177-1993 from these chromaticities, inverted.
//  * Acescg: ACEScg (Academy S-2014-004) AP1 primaries R (0.713, 0.293), G (0.165,
//    0.830), B (0.128, 0.044), with the ACES white (0.32168, 0.33767) of SMPTE ST 2065-1
//    (near D60). The spectrum's XYZ (D65-referred) is first adapted to the ACES white by
//    the Bradford transform (Lam 1985), the adaptation ACES itself uses between its white
//    and D65 (aces-dev ACESlib.Utilities_Color.ctl, calculate_cat_matrix with
//    CONE_RESP_MAT_BRADFORD) and that Blender's configuration applies to ACEScg
//    (OpenColorIO's "UTILITY - ACES-AP1_to_CIE-XYZ-D65_BFD"); so a D65 white, equal RGB in
//    Rec.709, stays equal RGB in ACEScg.
// Values are linear and unbounded: a colour outside a space's gamut has a negative
// channel there (what becomes of it is a later step's choice).
#pragma once

#include <array>
#include <string>
#include <string_view>

namespace welkin {

enum class ColorSpace { Rec709, Rec2020, Acescg };

using Matrix3 = std::array<std::array<double, 3>, 3>;

// "rec709", "rec2020", "acescg"; InvalidArgument naming `color_space` otherwise.
ColorSpace color_space_from_name(std::string_view name);
const char* color_space_name(ColorSpace space);

// An RGB space's chromaticities: (x, y) of its red, green, blue primaries and its white.
struct Chromaticities {
    std::array<double, 2> red, green, blue, white;
};
Chromaticities chromaticities(ColorSpace space);

// SMPTE RP 177-1993 normalised primary matrix: RGB -> XYZ (Y of white = 1) of a space
// with these chromaticities (the XYZ relative to its own white).
Matrix3 rgb_to_xyz_matrix(const Chromaticities& c);

// Bradford chromatic adaptation of XYZ from white `from` to white `to` (xy).
Matrix3 bradford_adaptation(std::array<double, 2> from, std::array<double, 2> to);

// The spectrum's XYZ (D65-referred) -> linear RGB of `space`.
Matrix3 xyz_to_rgb_matrix(ColorSpace space);

// Linear RGB of `from` -> linear RGB of `to`.
Matrix3 rgb_to_rgb_matrix(ColorSpace from, ColorSpace to);

Matrix3 multiply(const Matrix3& a, const Matrix3& b);
Matrix3 inverse(const Matrix3& m);
std::array<double, 3> mat_vec(const Matrix3& m, const std::array<double, 3>& v);

}  // namespace welkin
