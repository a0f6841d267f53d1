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
// separate "fma" target), so both give bit-identical results; on the build machine the
// AVX2 one takes ~20 % less time for the multiple-scattering and sky-view LUTs. Callees
// inlined into such a function are compiled for its target; WELKIN_ALWAYS_INLINE makes
// sure a helper pass is. Elsewhere (other processors or compilers) the macro is empty.
#if defined(__x86_64__) && defined(__linux__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define WELKIN_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef WELKIN_SIMD_CLONES
#define WELKIN_SIMD_CLONES
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

}  // namespace welkin
