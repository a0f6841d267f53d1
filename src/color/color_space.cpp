// SPDX-License-Identifier: Apache-2.0
// XYZ -> linear RGB of the output colour spaces; sources and derivations in color_space.hpp.
#include "welkin/color/color_space.hpp"

#include <cmath>

#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {
namespace {

// IEC 61966-2-1 XYZ -> linear sRGB (Rec.709 primaries, D65), four decimals: the matrix of
// Bruneton 2017's atmosphere/constants.h (XYZ_TO_SRGB).
constexpr Matrix3 kXyzToRec709 = {{{3.2406, -1.5372, -0.4986},  //
                                   {-0.9689, 1.8758, 0.0415},   //
                                   {0.0557, -0.2040, 1.0570}}};

constexpr std::array<double, 2> kD65 = {0.3127, 0.3290};          // ITU-R BT.709 / BT.2020
constexpr std::array<double, 2> kAcesWhite = {0.32168, 0.33767};  // SMPTE ST 2065-1

// Bradford's cone response matrix (Lam 1985), as aces-dev's CONE_RESP_MAT_BRADFORD.
constexpr Matrix3 kBradford = {{{0.8951, 0.2664, -0.1614},  //
                                {-0.7502, 1.7135, 0.0367},  //
                                {0.0389, -0.0685, 1.0296}}};

// XYZ with Y = 1 of chromaticity (x, y).
std::array<double, 3> xyz_of(std::array<double, 2> xy) {
    return {xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]};
}

}  // namespace

ColorSpace color_space_from_name(std::string_view name) {
    if (name == "rec709") return ColorSpace::Rec709;
    if (name == "rec2020") return ColorSpace::Rec2020;
    if (name == "acescg") return ColorSpace::Acescg;
    throw InvalidArgument("color_space", fmt::format("'{}' is not one of rec709, rec2020, acescg", name));
}

const char* color_space_name(ColorSpace space) {
    switch (space) {
        case ColorSpace::Rec2020:
            return "rec2020";
        case ColorSpace::Acescg:
            return "acescg";
        default:
            return "rec709";
    }
}

Chromaticities chromaticities(ColorSpace space) {
    switch (space) {
        case ColorSpace::Rec2020:  // ITU-R BT.2020-2, Table 3
            return {{0.708, 0.292}, {0.170, 0.797}, {0.131, 0.046}, kD65};
        case ColorSpace::Acescg:  // Academy S-2014-004 (AP1), SMPTE ST 2065-1 white
            return {{0.713, 0.293}, {0.165, 0.830}, {0.128, 0.044}, kAcesWhite};
        default:  // ITU-R BT.709-6, Table 1.3-1.4
            return {{0.640, 0.330}, {0.300, 0.600}, {0.150, 0.060}, kD65};
    }
}

Matrix3 multiply(const Matrix3& a, const Matrix3& b) {
    Matrix3 m{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) m[i][j] += a[i][k] * b[k][j];
    return m;
}

Matrix3 inverse(const Matrix3& m) {
    // The adjugate over the determinant.
    const auto c = [&](int i, int j) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
        return m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1];
    };
    const double det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    if (!(std::abs(det) > 1e-300)) throw InvalidArgument("matrix", "is singular");
    Matrix3 inv{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) inv[j][i] = c(i, j) / det;
    return inv;
}

std::array<double, 3> mat_vec(const Matrix3& m, const std::array<double, 3>& v) {
    return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],  //
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],  //
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
}

Matrix3 rgb_to_xyz_matrix(const Chromaticities& c) {
    // SMPTE RP 177-1993, sec. 3.3: P holds the primaries' XYZ (Y = 1) as columns; the
    // scales S = P^-1 W make R = G = B = 1 the white W (Y = 1); NPM = P diag(S).
    const std::array<double, 3> r = xyz_of(c.red), g = xyz_of(c.green), b = xyz_of(c.blue);
    const Matrix3 p = {{{r[0], g[0], b[0]}, {r[1], g[1], b[1]}, {r[2], g[2], b[2]}}};
    const std::array<double, 3> s = mat_vec(inverse(p), xyz_of(c.white));
    Matrix3 npm{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) npm[i][j] = p[i][j] * s[j];
    return npm;
}

Matrix3 bradford_adaptation(std::array<double, 2> from, std::array<double, 2> to) {
    // Von Kries scaling in Bradford's cone space: M^-1 diag(rho_to / rho_from) M.
    const std::array<double, 3> a = mat_vec(kBradford, xyz_of(from)), b = mat_vec(kBradford, xyz_of(to));
    const Matrix3 scale = {{{b[0] / a[0], 0.0, 0.0}, {0.0, b[1] / a[1], 0.0}, {0.0, 0.0, b[2] / a[2]}}};
    return multiply(inverse(kBradford), multiply(scale, kBradford));
}

Matrix3 xyz_to_rgb_matrix(ColorSpace space) {
    if (space == ColorSpace::Rec709) return kXyzToRec709;
    const Chromaticities c = chromaticities(space);
    const Matrix3 to_rgb = inverse(rgb_to_xyz_matrix(c));
    if (c.white == kD65) return to_rgb;
    return multiply(to_rgb, bradford_adaptation(kD65, c.white));
}

Matrix3 rgb_to_rgb_matrix(ColorSpace from, ColorSpace to) {
    return multiply(xyz_to_rgb_matrix(to), inverse(xyz_to_rgb_matrix(from)));
}

}  // namespace welkin
