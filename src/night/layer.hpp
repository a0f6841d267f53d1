// SPDX-License-Identifier: Apache-2.0
// The night layer's images added to a rendered sky (the stars, the night glow, the moon's
// disc: stars.cpp, night_glow.cpp, moonlit_sky.cpp): equirectangular, `width` x width / 2
// pixels of `channels` floats, added as the sky's own light is, under the clouds.
#pragma once

#include <cstddef>
#include <vector>

#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/render/sky_image.hpp"

namespace welkin::night {

// A black layer; throws InvalidArgument naming `width` unless it is even and in [4, 16384].
inline std::vector<float> blank_layer(int width, std::size_t channels) {
    if (width < 4 || width > 16384 || width % 2 != 0)
        throw InvalidArgument("width", fmt::format("must be even and in [4, 16384], got {}", width));
    return std::vector<float>(std::size_t(width) * std::size_t(width / 2) * channels, 0.0f);
}

// image += exposure x the clouds' transmittance x layer, pixel by pixel (the layer in the
// image's channels).
inline void add_under_clouds(SkyImage& image, const std::vector<float>& layer, double exposure) {
    const std::size_t nc = image.channels();
    const float e = float(exposure);
    for (std::size_t p = 0; p < layer.size() / nc; ++p) {
        const float t = image.cloud_transmittance.empty() ? 1.0f : image.cloud_transmittance[p];
        for (std::size_t c = 0; c < nc; ++c) image.pixels[p * nc + c] += e * t * layer[p * nc + c];
    }
}

}  // namespace welkin::night
