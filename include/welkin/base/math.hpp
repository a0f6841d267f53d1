// SPDX-License-Identifier: Apache-2.0
// Small numeric helpers that keep the physics out of trouble near its domain edges.
//
// As in Bruneton's implementation, every cosine that comes out of arithmetic is clamped
// to [-1, 1] and every square root takes max(0, x): rounding must never turn a grazing
// ray into a NaN.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace welkin {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2.0 * kPi;
inline constexpr double kFourPi = 4.0 * kPi;
inline constexpr double kDegree = kPi / 180.0;

template <class T>
inline T clamp_cosine(T mu) {
    return std::clamp(mu, T(-1), T(1));
}

template <class T>
inline T safe_sqrt(T x) {
    return std::sqrt(std::max(x, T(0)));
}

template <class T>
inline T clamp01(T x) {
    return std::clamp(x, T(0), T(1));
}

// min, max and clamp by value, written as selects: std::min and std::clamp return
// references, which keeps GCC from turning a loop of them into SIMD code.
template <class T>
inline T min_value(T a, T b) {
    return b < a ? b : a;
}
template <class T>
inline T max_value(T a, T b) {
    return a < b ? b : a;
}
template <class T>
inline T clamp_value(T x, T lo, T hi) {
    return min_value(max_value(x, lo), hi);
}

// floor(x) as an integer, for |x| < 2^63 (where the conversion is defined): the truncation,
// one less where it rounded up. The same value as std::int64_t(std::floor(x)) in a few
// instructions, where without SSE4.1 std::floor is a longer sequence.
inline std::int64_t floor_to_int64(double x) {
    const std::int64_t i = static_cast<std::int64_t>(x);
    return i - static_cast<std::int64_t>(x < static_cast<double>(i));
}

// a mod n in [0, n) for n > 0 (C++'s % keeps the sign of a): the index of a periodic table.
template <class T>
inline T wrap_index(T a, T n) {
    const T r = a % n;
    return r < T(0) ? r + n : r;
}

}  // namespace welkin
