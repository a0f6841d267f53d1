// SPDX-License-Identifier: Apache-2.0
// From spectral radiance to linear RGB (Rec.709 and the other spaces of color_space.hpp).
//
// Units: linear Rec.709 (sRGB primaries, D65 white, no white balance, no gamma) or another
// linear space of color_space.hpp (the same XYZ through its matrix), in
// W m^-2 sr^-1, CIE-weighted without the 683 lm/W factor — the convention of
// tests/data and the scale of Blender's Nishita sky.
//
// Two paths land in the same units:
//  * many wavelengths (the spectral mode): X = integral of L(lambda) xbar(lambda) dlambda
//    over 360..830 nm, likewise Y and Z, with L the linear interpolant of the samples
//    (constant beyond the end samples, as Bruneton's ConvertSpectrumToLinearSrgb), then
//    XYZ -> Rec.709;
//  * three wavelengths: Bruneton 2017's "approximate" conversion (Model's
//    ComputeSpectralRadianceToLuminanceFactors): channel j keeps its sample L(lambda_j)
//    and assumes the spectrum around it is the solar spectrum tilted by a power of the
//    wavelength, L(lambda) = L(lambda_j) * E(lambda)/E(lambda_j) * (lambda/lambda_j)^p,
//    integrated against the Rec.709 colour-matching function of that channel. p = -3 for
//    sky radiance (between Rayleigh's -4 and Mie's 0), p = 0 for sunlight.
//
// The colour-matching functions are the multi-lobe Gaussian fit of Wyman, Sloan and
// Shirley 2013, "Simple Analytic Approximations to the CIE XYZ Color Matching Functions"
// (JCGT 2(2)), which follows the CIE 1931 2-degree tables to within 1.5 % of their
// peak (measured in tests/cpp/test_color.cpp; worst: xbar at 630 nm).
#pragma once

#include <array>
#include <span>
#include <vector>

#include "welkin/color/color_space.hpp"
#include "welkin/color/spectral_data.hpp"

namespace welkin {

struct Xyz {
    double x, y, z;
};

// CIE 1931 2-degree colour-matching functions (Wyman et al. 2013 fit).
Xyz cie1931_cmf(double wavelength_nm);

// XYZ -> linear Rec.709 (IEC 61966-2-1 matrix).
std::array<double, 3> xyz_to_rec709(const Xyz& xyz);

// Converts (N, C) spectral radiance at `wavelengths_nm` to (N, 3) linear RGB of `space`
// (color_space.hpp; Rec.709 by default): the spectrum's XYZ by one of the two paths above,
// then the space's matrix. The only place where spectra become RGB.
class SpectrumToRgb {
public:
    // `lambda_power`: p of the three-sample conversion (-3 for sky, 0 for sun); unused
    // when there are more than three wavelengths. Throws InvalidArgument if the
    // wavelengths are not strictly increasing or decreasing, or C < 3.
    SpectrumToRgb(std::span<const double> wavelengths_nm, double lambda_power = -3.0,
                  ColorSpace space = ColorSpace::Rec709);

    // gamut_map(M * spectrum) (gamut.hpp): never a negative channel.
    std::array<double, 3> convert(std::span<const float> spectrum) const;
    void convert(std::span<const float> spectra, std::span<float> rgb_out) const;  // (N,C)->(N,3)

    // rgb = M * spectrum before the gamut mapping: the 3 x C matrix. Whoever applies it
    // directly applies gamut_map() to what it outputs.
    const std::vector<double>& matrix() const { return matrix_; }
    std::size_t channels() const { return channels_; }
    ColorSpace space() const { return space_; }
    // The space's luminance weights (the Y row of its RGB -> XYZ), for gamut_map.
    const std::array<double, 3>& luminance_weights() const { return luminance_; }

private:
    void build_rec709(std::span<const double> wavelengths_nm, double lambda_power);

    std::size_t channels_;
    ColorSpace space_;
    std::array<double, 3> luminance_;
    std::vector<double> matrix_;  // 3 x C, row-major
};

}  // namespace welkin
