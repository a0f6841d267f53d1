// SPDX-License-Identifier: Apache-2.0
// Four floats in one SIMD register, for the few inner loops of the LUT builds.
//
// Spectrum4 (glm::vec4) arithmetic is written component by component; GCC turns it into
// SIMD code in straight-line code but often not inside a loop that accumulates, where it
// then spends four scalar instructions per operation. Float4 is the GCC/Clang vector
// extension (SSE on x86-64, NEON on ARM), whose +, -, * are one instruction each and
// accept a scalar on either side (broadcast). Conversions to and from Spectrum4 are copies
// of the same 16 bytes.
#pragma once

#include <cstring>

#include <glm/vec4.hpp>

// WELKIN_SIMD_CLONES marks the few hot loops of the LUT builds for function
// multi-versioning: on x86-64 the compiler builds them twice, for the baseline (SSE2) and
// for AVX2, and the loader picks the one the processor runs (an ifunc, resolved once).
// The AVX2 build does the same IEEE operations in the same order, four or eight lanes at a
// time with three-operand instructions, and uses no fused multiply-add (that is the
// separate "fma" target), so both give bit-identical results (what each build gains:
// docs/validation.md#sky-speed). Callees
// inlined into such a function are compiled for its target; WELKIN_ALWAYS_INLINE makes
// sure a helper pass is. Elsewhere (other processors or compilers) the macro is empty.
// (Defining it empty on the command line, -DWELKIN_SIMD_CLONES=, builds the baseline only.)
#ifndef WELKIN_SIMD_CLONES
#if defined(__x86_64__) && defined(__linux__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define WELKIN_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#endif
#ifndef WELKIN_SIMD_CLONES
#define WELKIN_SIMD_CLONES
#endif
// WELKIN_SIMD_CLONES_WIDE adds an AVX-512 build for loops of float arithmetic (the sun
// lookups' coordinates of the multiple-scattering and sky-view LUTs), which do sixteen
// lanes at a time there. The transmittance LUT's loop, in double, gains nothing from it
// and keeps WELKIN_SIMD_CLONES. The same IEEE operations again: AVX-512F has fused
// multiply-adds, which the core's -ffp-contract=off (CMakeLists.txt) keeps GCC from using
// for a * b + c.
#ifndef WELKIN_SIMD_CLONES_WIDE
#if defined(__x86_64__) && defined(__linux__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define WELKIN_SIMD_CLONES_WIDE __attribute__((target_clones("avx512f", "avx2", "default")))
#endif
#endif
#endif
#ifndef WELKIN_SIMD_CLONES_WIDE
#define WELKIN_SIMD_CLONES_WIDE
#endif
#define WELKIN_ALWAYS_INLINE inline __attribute__((always_inline))

namespace welkin {

using Float4 = float __attribute__((vector_size(16)));

inline Float4 to_float4(const glm::vec4& v) {
    Float4 f;
    std::memcpy(&f, &v, sizeof f);
    return f;
}

inline glm::vec4 to_vec4(const Float4& f) {
    glm::vec4 v;
    std::memcpy(&v, &f, sizeof v);
    return v;
}

using Int4 = int __attribute__((vector_size(16)));

// e^x in all four lanes at once, for x <= 0 (transmittances exp(-tau)): Cody and Waite's
// range reduction x = k ln 2 + r, |r| <= ln 2 / 2, with ln 2 split in two floats so that
// k ln 2 is exact to float precision for the k that occur, then e^r by the degree-7
// minimax polynomial of Cephes' expf (S. Moshier, Cephes Math Library; 1 + r + r^2 / 2 +
// r^3 c_3 + ...), and 2^k put into the exponent bits. Relative error below the float
// epsilon 1.19e-7 (measured worst 8.1e-8; tests/cpp/test_simd.cpp checks it against
// std::exp in double over [-87, 0]); 1 at x = 0 exactly. Below x = -87.3, where e^x leaves the normal floats
// (< 1.2e-38), it returns 0. Round-to-nearest of x / ln 2 is the "add 1.5 * 2^23" trick,
// exact for |x / ln 2| < 2^22 in the default rounding mode.
inline Float4 exp_nonpositive(Float4 x) {
    const Float4 underflow = {-87.33f, -87.33f, -87.33f, -87.33f};
    const Int4 dead = x < underflow;
    x = x < underflow ? underflow : x;
    const float kRound = 12582912.0f;                               // 1.5 * 2^23
    const Float4 k = (x * 1.44269504088896341f + kRound) - kRound;  // nearest integer to x / ln 2
    const Float4 r = (x - k * 0.693359375f) - k * -2.12194440e-4f;  // ln 2 = 0.693359375 - 2.12194440e-4
    const Float4 r2 = r * r;
    Float4 p = 1.9875691500e-4f * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    p = p * r2 + r + 1.0f;
    // 2^k: k + 127 in the exponent field (k >= -126 here, so the result stays normal).
    const Int4 bits = (__builtin_convertvector(k, Int4) + 127) << 23;
    Float4 scale;
    std::memcpy(&scale, &bits, sizeof scale);
    const Float4 result = p * scale;
    return dead ? Float4{0.0f, 0.0f, 0.0f, 0.0f} : result;
}

}  // namespace welkin
