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
