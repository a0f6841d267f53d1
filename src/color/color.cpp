// Spectral radiance to linear Rec.709; see color.hpp for the two paths and their units.
#include "welkin/color/color.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/base/error.hpp"

namespace welkin {
namespace {

// Wyman, Sloan & Shirley 2013, sec. 2.2, the multi-lobe fit: each colour-matching
// function is a sum of piecewise Gaussians
//     g(lambda; mu, s1, s2) = exp(-(lambda - mu)^2 / (2 s^2)),  s = s1 if lambda < mu
//                                                                 s = s2 otherwise,
// with (amplitude, mu, s1, s2) from their Table 1 (CIE 1931 2-degree observer):
//     xbar = 1.056 g(599.8, 37.9, 31.0) + 0.362 g(442.0, 16.0, 26.7)
//            - 0.065 g(501.1, 20.4, 26.2)
//     ybar = 0.821 g(568.8, 46.9, 40.5) + 0.286 g(530.9, 16.3, 31.1)
//     zbar = 1.217 g(437.0, 11.8, 36.0) + 0.681 g(459.0, 26.0, 13.8)
double lobe(double lambda, double mu, double s1, double s2) {
    const double t = (lambda - mu) / (lambda < mu ? s1 : s2);
    return std::exp(-0.5 * t * t);
}

// Bruneton 2017 (atmosphere/model.cc) integrates the three-sample factors from
// kLambdaMin = 360 to kLambdaMax = 830 nm, exclusive, in 1 nm steps: the range of the
// CIE 1931 tables. The spectral path integrates over the same range.
constexpr double kCieMinNm = 360.0;
constexpr double kCieMaxNm = 830.0;

// IEC 61966-2-1 XYZ -> linear sRGB (= Rec.709 primaries, D65), the matrix of Bruneton's
// atmosphere/constants.h (XYZ_TO_SRGB).
constexpr double kXyzToRec709[9] = {3.2406, -1.5372, -0.4986,   //
                                    -0.9689, 1.8758, 0.0415,    //
                                    0.0557,  -0.2040, 1.0570};

// Rec.709 colour-matching functions: rbar = M xbar (one row of XYZ -> Rec.709 per channel).
std::array<double, 3> rec709_cmf(double lambda) {
    const Xyz c = cie1931_cmf(lambda);
    return xyz_to_rec709(c);
}

}  // namespace

Xyz cie1931_cmf(double lambda) {
    return {1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7) -
                0.065 * lobe(lambda, 501.1, 20.4, 26.2),
            0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1),
            1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8)};
}

std::array<double, 3> xyz_to_rec709(const Xyz& c) {
    const double* m = kXyzToRec709;
    return {m[0] * c.x + m[1] * c.y + m[2] * c.z,  //
            m[3] * c.x + m[4] * c.y + m[5] * c.z,  //
            m[6] * c.x + m[7] * c.y + m[8] * c.z};
}

SpectrumToRgb::SpectrumToRgb(std::span<const double> wavelengths_nm, double lambda_power)
    : channels_(wavelengths_nm.size()) {
    const std::size_t n = channels_;
    if (n < 3)
        throw InvalidArgument("wavelengths_nm",
                              fmt::format("conversion to RGB needs at least 3 wavelengths, got {}",
                                          n));
    for (std::size_t i = 0; i < n; ++i)
        require_in_range(fmt::format("wavelengths_nm[{}]", i), wavelengths_nm[i], 1.0, 1e5,
                         "nm");
    require_in_range("lambda_power", lambda_power, -10.0, 10.0);
    const bool increasing = wavelengths_nm[1] > wavelengths_nm[0];
    for (std::size_t i = 1; i < n; ++i)
        if ((wavelengths_nm[i] > wavelengths_nm[i - 1]) != increasing ||
            wavelengths_nm[i] == wavelengths_nm[i - 1])
            throw InvalidArgument("wavelengths_nm",
                                  "must be strictly increasing or strictly decreasing");

    // Work on increasing wavelengths; `order[k]` is the input index of the k-th smallest.
    std::vector<std::size_t> order(n);
    for (std::size_t k = 0; k < n; ++k) order[k] = increasing ? k : n - 1 - k;
    std::vector<double> w(n);
    for (std::size_t k = 0; k < n; ++k) w[k] = wavelengths_nm[order[k]];

    matrix_.assign(3 * n, 0.0);
    if (n == 3) {
        // Bruneton 2017, Model::ComputeSpectralRadianceToLuminanceFactors: the channel of
        // wavelength lambda_j (R the longest, B the shortest) keeps L(lambda_j) and
        // assumes L(lambda) = L(lambda_j) E(lambda)/E(lambda_j) (lambda/lambda_j)^p, so
        //     rgb_j = L(lambda_j) * sum_lambda cmf_j(lambda) E(lambda)/E(lambda_j)
        //                                     (lambda/lambda_j)^p * 1 nm,
        // lambda = 360, 361, ..., 829 nm; E is the ASTM G-173 solar spectrum. The result is
        // a diagonal matrix: each channel depends on one sample only.
        for (int j = 0; j < 3; ++j) {
            const double lj = w[2 - j];  // R <- longest, G <- middle, B <- shortest
            const double ej = solar_irradiance_astm_g173(lj);
            double k = 0.0;
            for (double lambda = kCieMinNm; lambda < kCieMaxNm; lambda += 1.0)
                k += rec709_cmf(lambda)[j] * solar_irradiance_astm_g173(lambda) / ej *
                     std::pow(lambda / lj, lambda_power);
            matrix_[j * n + order[2 - j]] = k;  // times 1 nm
        }
        return;
    }

    // Many wavelengths: X = integral over [360, 830] nm of L(lambda) xbar(lambda), where L
    // is the linear interpolant of the samples, held constant beyond the end samples (as
    // Bruneton's Model::ConvertSpectrumToLinearSrgb and the peer data in
    // tests/data do). L is linear in its samples, L = sum_i L_i hat_i(lambda)
    // with hat_i the interpolation's tent functions, so each column of the matrix is
    // M * integral(hat_i cmf); the integral runs by the trapezoid rule on a 0.25 nm grid,
    // which resolves the narrowest lobe of the functions (zbar, sigma 11.8 nm) to ~1e-5.
    // This integrates the colour-matching functions exactly between the samples instead
    // of sampling them only at 10 nm apart (which errs by ~1 % on the blue lobe).
    const double step = 0.25;
    const int steps = int(std::lround((kCieMaxNm - kCieMinNm) / step));
    std::vector<double> tent(n);
    for (int s = 0; s <= steps; ++s) {
        const double lambda = kCieMinNm + step * s;
        const double weight = (s == 0 || s == steps) ? 0.5 * step : step;
        const std::array<double, 3> cmf = rec709_cmf(lambda);
        // Tent functions at lambda: nonzero for at most the two bracketing samples.
        std::fill(tent.begin(), tent.end(), 0.0);
        if (lambda <= w.front()) {
            tent[0] = 1.0;
        } else if (lambda >= w.back()) {
            tent[n - 1] = 1.0;
        } else {
            const std::size_t i = std::size_t(std::upper_bound(w.begin(), w.end(), lambda) -
                                              w.begin()) - 1;
            const double f = (lambda - w[i]) / (w[i + 1] - w[i]);
            tent[i] = 1.0 - f;
            tent[i + 1] = f;
        }
        for (std::size_t k = 0; k < n; ++k) {
            if (tent[k] == 0.0) continue;
            for (int j = 0; j < 3; ++j) matrix_[j * n + order[k]] += weight * tent[k] * cmf[j];
        }
    }
}

std::array<double, 3> SpectrumToRgb::convert(std::span<const float> spectrum) const {
    if (spectrum.size() != channels_)
        throw InvalidArgument("spectrum", fmt::format("needs {} values, got {}", channels_,
                                                      spectrum.size()));
    std::array<double, 3> rgb{0.0, 0.0, 0.0};
    for (int j = 0; j < 3; ++j)
        for (std::size_t c = 0; c < channels_; ++c)
            rgb[j] += matrix_[j * channels_ + c] * double(spectrum[c]);
    return rgb;
}

void SpectrumToRgb::convert(std::span<const float> spectra, std::span<float> rgb_out) const {
    const std::size_t n = channels_;
    if (spectra.size() % n != 0)
        throw InvalidArgument("spectra", fmt::format("size {} is not a multiple of the {} "
                                                     "channels", spectra.size(), n));
    const std::size_t count = spectra.size() / n;
    if (rgb_out.size() != 3 * count)
        throw InvalidArgument("rgb_out", fmt::format("needs {} values (3 per spectrum), got {}",
                                                     3 * count, rgb_out.size()));
    const double* m = matrix_.data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i != range.end(); ++i) {
                              const float* s = spectra.data() + i * n;
                              for (int j = 0; j < 3; ++j) {
                                  double sum = 0.0;
                                  for (std::size_t c = 0; c < n; ++c) sum += m[j * n + c] * s[c];
                                  rgb_out[3 * i + j] = float(sum);
                              }
                          }
                      });
}

}  // namespace welkin
