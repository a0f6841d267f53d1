// SPDX-License-Identifier: Apache-2.0
// A 2D table of Spectrum4 with bilinear lookup at texel centres, as a GPU texture with
// clamp-to-edge addressing: texel (i, j) holds the value at u = (i + 0.5) / width,
// v = (j + 0.5) / height.
#pragma once

#include <algorithm>
#include <vector>

#include "welkin/atmosphere/batch.hpp"
#include "welkin/base/math.hpp"
#include "welkin/base/simd.hpp"

namespace welkin {

class Texture2D {
public:
    Texture2D() = default;
    Texture2D(int width, int height) : width_(width), height_(height), texels_(std::size_t(width) * height) {}

    int width() const { return width_; }
    int height() const { return height_; }
    Spectrum4& at(int i, int j) { return texels_[std::size_t(j) * width_ + i]; }
    const Spectrum4& at(int i, int j) const { return texels_[std::size_t(j) * width_ + i]; }

    Spectrum4 sample(float u, float v) const {
        const float x = std::clamp(u * float(width_) - 0.5f, 0.0f, float(width_ - 1));
        const float y = std::clamp(v * float(height_) - 0.5f, 0.0f, float(height_ - 1));
        const int i = std::min(int(x), width_ - 2 < 0 ? 0 : width_ - 2);
        const int j = std::min(int(y), height_ - 2 < 0 ? 0 : height_ - 2);
        const float fx = x - float(i), fy = y - float(j);
        const int i1 = std::min(i + 1, width_ - 1), j1 = std::min(j + 1, height_ - 1);
        const Spectrum4 a = at(i, j) + fx * (at(i1, j) - at(i, j));
        const Spectrum4 b = at(i, j1) + fx * (at(i1, j1) - at(i, j1));
        return a + fy * (b - a);
    }

    // The same bilinear lookup split for loops that read many texels at one v: Row holds
    // the two texel rows and the weight between them, and Row::sample takes the texel-space
    // coordinate x = u * width - 0.5 (so x = 0 and x = width - 1 are the first and last
    // texel centres). sample(u, v) == row(v).sample(u * width - 0.5f) for textures of at
    // least 2 x 2 texels (the LUT sizes are at least 4).
    struct Row {
        const Spectrum4* lo;
        const Spectrum4* hi;
        float fy;
        int last;  // width - 1

        // x (clamped to the texels) as the left texel i and the weight fx of the right one;
        // arithmetic only, so a loop of them vectorises.
        static void split(float x_in, int last, int& i, float& fx) {
            const float x = clamp_value(x_in, 0.0f, float(last));
            i = int(min_value(x, float(last - 1)));
            fx = x - float(i);
        }
        Float4 sample4(int i, float fx) const {
            const Float4 l0 = to_float4(lo[i]), l1 = to_float4(lo[i + 1]);
            const Float4 h0 = to_float4(hi[i]), h1 = to_float4(hi[i + 1]);
            const Float4 a = l0 + fx * (l1 - l0), b = h0 + fx * (h1 - h0);
            return a + fy * (b - a);
        }
        Float4 sample4(float x) const {
            int i;
            float fx;
            split(x, last, i, fx);
            return sample4(i, fx);
        }
        Spectrum4 sample(float x) const { return to_vec4(sample4(x)); }
    };
    Row row(float v) const {
        const float y = std::clamp(v * float(height_) - 0.5f, 0.0f, float(height_ - 1));
        const int j = std::min(int(y), height_ - 2);
        return {&at(0, j), &at(0, j + 1), y - float(j), width_ - 1};
    }

private:
    int width_ = 0, height_ = 0;
    std::vector<Spectrum4> texels_;
};

// Bruneton 2017 (functions.glsl, GetTextureCoordFromUnitRange): maps x in [0, 1] so that
// 0 and 1 fall on the centres of the first and last texels, where values are exact.
inline float texcoord_from_unit(float x, int size) {
    return 0.5f / float(size) + x * (1.0f - 1.0f / float(size));
}
inline float unit_from_texcoord(float u, int size) {
    return (u - 0.5f / float(size)) / (1.0f - 1.0f / float(size));
}

}  // namespace welkin
