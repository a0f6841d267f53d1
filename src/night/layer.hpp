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

// Throws InvalidArgument naming `width` unless it is even and in [4, 16384].
inline void require_layer_width(int width) {
    if (width < 4 || width > 16384 || width % 2 != 0)
        throw InvalidArgument("width", fmt::format("must be even and in [4, 16384], got {}", width));
}

// A black layer of `width` x width / 2 pixels of `channels` floats.
inline std::vector<float> blank_layer(int width, std::size_t channels) {
    require_layer_width(width);
    return std::vector<float>(std::size_t(width) * std::size_t(width / 2) * channels, 0.0f);
}

// Where a layer's light goes, pixel by pixel: pixels[p, c] += scale x t[p] x value, with t
// the clouds' transmittance at the pixel (1 without clouds). Into a blank layer (scale 1,
// no clouds) it writes the layer itself; into a rendered image (scale: the exposure) it
// adds the layer as add_under_clouds does, with no layer-sized buffer in between.
struct LayerSink {
    float* pixels = nullptr;
    std::size_t channels = 0;
    const float* transmittance = nullptr;  // per pixel, or none
    float scale = 1.0f;

    void add(std::size_t pixel, std::size_t channel, float value) const {
        const float t = transmittance ? transmittance[pixel] : 1.0f;
        pixels[pixel * channels + channel] += scale * t * value;
    }
};

inline LayerSink sink_into(std::vector<float>& layer, std::size_t channels) {
    return {layer.data(), channels, nullptr, 1.0f};
}

inline LayerSink sink_into(SkyImage& image, double exposure) {
    require_layer_width(image.width);
    return {image.pixels.data(), image.channels(),
            image.cloud_transmittance.empty() ? nullptr : image.cloud_transmittance.data(), float(exposure)};
}

// image += exposure x the clouds' transmittance x layer, pixel by pixel (the layer in the
// image's channels).
inline void add_under_clouds(SkyImage& image, const std::vector<float>& layer, double exposure) {
    const LayerSink sink = sink_into(image, exposure);
    for (std::size_t p = 0; p < layer.size() / sink.channels; ++p)
        for (std::size_t c = 0; c < sink.channels; ++c) sink.add(p, c, layer[p * sink.channels + c]);
}

}  // namespace welkin::night
