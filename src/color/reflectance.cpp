// SPDX-License-Identifier: Apache-2.0
// RGB -> reflectance spectrum by Jakob & Hanika 2019's sigmoid; see reflectance.hpp.
#include "welkin/color/reflectance.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/color/color.hpp"

namespace welkin {
namespace {

// The colour integrals run over the CIE 1931 tables' range every 1 nm.
constexpr double kLo = 360.0, kHi = 830.0;
constexpr std::size_t kSamples = 471;

double grid(std::size_t i) { return kLo + double(i); }
double scaled(double lambda) { return (lambda - kLo) / (kHi - kLo); }

// S(x) of the header and its derivative; |x| is bounded by the fit, so x^2 stays finite.
double sigmoid(double x) { return 0.5 + 0.5 * x / std::sqrt(1.0 + x * x); }
double sigmoid_slope(double x) { return 0.5 / std::pow(1.0 + x * x, 1.5); }

// The 3 x kSamples matrix A with rgb = A R for a reflectance R on the grid: the space's
// RGB of R (XYZ by the rectangle rule, then the space's matrix), each channel divided by
// that of R = 1 (the perfect white reflector).
struct Balance {
    std::array<std::array<double, kSamples>, 3> a{};
};

Balance make_balance(ColorSpace space) {
    const Matrix3 m = xyz_to_rgb_matrix(space);
    Balance b;
    std::array<double, 3> white{};
    for (std::size_t i = 0; i < kSamples; ++i) {
        const Xyz c = cie1931_cmf(grid(i));
        const std::array<double, 3> rgb = mat_vec(m, {c.x, c.y, c.z});
        for (int k = 0; k < 3; ++k) {
            b.a[k][i] = rgb[k];
            white[k] += rgb[k];
        }
    }
    for (int k = 0; k < 3; ++k)
        for (double& v : b.a[k]) v /= white[k];
    return b;
}

const Balance& balance(ColorSpace space) {
    static const Balance rec709 = make_balance(ColorSpace::Rec709);
    static const Balance rec2020 = make_balance(ColorSpace::Rec2020);
    static const Balance acescg = make_balance(ColorSpace::Acescg);
    switch (space) {
        case ColorSpace::Rec2020:
            return rec2020;
        case ColorSpace::Acescg:
            return acescg;
        case ColorSpace::Rec709:
            break;
    }
    return rec709;
}

double quadratic(const std::array<double, 3>& c, double t) { return (c[0] * t + c[1]) * t + c[2]; }

// rgb of the sigmoid spectrum with coefficients c, and the residual's squared norm.
std::array<double, 3> sigmoid_rgb(const Balance& b, const std::array<double, 3>& c) {
    std::array<double, 3> rgb{};
    for (std::size_t i = 0; i < kSamples; ++i) {
        const double r = sigmoid(quadratic(c, scaled(grid(i))));
        for (int k = 0; k < 3; ++k) rgb[k] += b.a[k][i] * r;
    }
    return rgb;
}

double squared_error(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    double e = 0.0;
    for (int k = 0; k < 3; ++k) e += (a[k] - b[k]) * (a[k] - b[k]);
    return e;
}

// Levenberg-Marquardt on the three coefficients (Jakob & Hanika 2019, sec. 4: Gauss-Newton
// from a flat start). Returns the coefficients of least RGB error found.
std::array<double, 3> fit(const Balance& b, const std::array<double, 3>& target) {
    const double mean = std::clamp((target[0] + target[1] + target[2]) / 3.0, 0.01, 0.99);
    const double u = 2.0 * mean - 1.0;  // S(x) = mean  <=>  x = u / sqrt(1 - u^2)
    std::array<double, 3> c{0.0, 0.0, u / std::sqrt(1.0 - u * u)};
    double err = squared_error(sigmoid_rgb(b, c), target);
    double damping = 1e-3;
    constexpr double kBound = 1e4;  // the coefficients' range: keeps x^2 finite
    for (int iteration = 0; iteration < 200 && err > 1e-20; ++iteration) {
        // J = d rgb / d c, r = rgb - target.
        Matrix3 j{};
        std::array<double, 3> rgb{};
        for (std::size_t i = 0; i < kSamples; ++i) {
            const double t = scaled(grid(i)), x = quadratic(c, t);
            const double r = sigmoid(x), s = sigmoid_slope(x);
            const std::array<double, 3> dx{t * t, t, 1.0};
            for (int k = 0; k < 3; ++k) {
                rgb[k] += b.a[k][i] * r;
                for (int n = 0; n < 3; ++n) j[k][n] += b.a[k][i] * s * dx[n];
            }
        }
        std::array<double, 3> residual{};
        for (int k = 0; k < 3; ++k) residual[k] = rgb[k] - target[k];
        // (J^T J + damping diag(J^T J)) step = -J^T r.
        Matrix3 normal{};
        std::array<double, 3> gradient{};
        for (int n = 0; n < 3; ++n) {
            for (int k = 0; k < 3; ++k) gradient[n] += j[k][n] * residual[k];
            for (int m = 0; m < 3; ++m)
                for (int k = 0; k < 3; ++k) normal[n][m] += j[k][n] * j[k][m];
        }
        bool improved = false;
        for (int attempt = 0; attempt < 30 && !improved; ++attempt) {
            Matrix3 damped = normal;
            for (int n = 0; n < 3; ++n) damped[n][n] += damping * std::max(normal[n][n], 1e-30);
            const std::array<double, 3> step = mat_vec(inverse(damped), gradient);
            std::array<double, 3> next{};
            for (int n = 0; n < 3; ++n) next[n] = std::clamp(c[n] - step[n], -kBound, kBound);
            const double next_err = squared_error(sigmoid_rgb(b, next), target);
            if (std::isfinite(next_err) && next_err < err) {
                c = next;
                improved = err - next_err > 1e-16 * err;
                err = next_err;
                damping = std::max(damping * 0.3, 1e-12);
                if (!improved) return c;  // no longer moving
            } else {
                damping *= 10.0;
            }
        }
        if (!improved) break;
    }
    return c;
}

}  // namespace

std::vector<double> rgb_to_reflectance(const std::array<double, 3>& rgb,
                                       std::span<const double> wavelengths_nm, ColorSpace space,
                                       const char* parameter) {
    for (int k = 0; k < 3; ++k)
        if (!(std::isfinite(rgb[k]) && rgb[k] >= 0.0 && rgb[k] <= 1.0))
            throw InvalidArgument(parameter,
                                  fmt::format("every channel must be in [0, 1] (a reflectance), got "
                                              "({}, {}, {})",
                                              rgb[0], rgb[1], rgb[2]));
    if (wavelengths_nm.empty()) throw InvalidArgument("wavelengths_nm", "must not be empty");
    for (double l : wavelengths_nm)
        if (!std::isfinite(l)) throw InvalidArgument("wavelengths_nm", "every wavelength must be finite");
    // A grey is the flat spectrum of its value (header), black and white included.
    if (rgb[0] == rgb[1] && rgb[1] == rgb[2]) return std::vector<double>(wavelengths_nm.size(), rgb[0]);
    const std::array<double, 3> c = fit(balance(space), rgb);
    std::vector<double> out;
    out.reserve(wavelengths_nm.size());
    for (double l : wavelengths_nm) out.push_back(sigmoid(quadratic(c, scaled(std::clamp(l, kLo, kHi)))));
    return out;
}

std::array<double, 3> reflectance_to_rgb(std::span<const double> reflectance,
                                         std::span<const double> wavelengths_nm, ColorSpace space) {
    if (reflectance.size() != wavelengths_nm.size() || reflectance.empty())
        throw InvalidArgument("reflectance", fmt::format("needs one value per wavelength ({}), got {}",
                                                         wavelengths_nm.size(), reflectance.size()));
    // Linear interpolation in wavelength order (constant beyond the ends).
    std::vector<std::size_t> order(wavelengths_nm.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return wavelengths_nm[a] < wavelengths_nm[b]; });
    const Balance& b = balance(space);
    std::array<double, 3> rgb{};
    for (std::size_t i = 0; i < kSamples; ++i) {
        const double l = grid(i);
        double r = reflectance[order.front()];
        if (l >= wavelengths_nm[order.back()]) {
            r = reflectance[order.back()];
        } else if (l > wavelengths_nm[order.front()]) {
            std::size_t n = 1;
            while (wavelengths_nm[order[n]] < l) ++n;
            const double l0 = wavelengths_nm[order[n - 1]], l1 = wavelengths_nm[order[n]];
            const double f = l1 > l0 ? (l - l0) / (l1 - l0) : 0.0;
            r = reflectance[order[n - 1]] * (1.0 - f) + reflectance[order[n]] * f;
        }
        for (int k = 0; k < 3; ++k) rgb[k] += b.a[k][i] * r;
    }
    return rgb;
}

}  // namespace welkin
