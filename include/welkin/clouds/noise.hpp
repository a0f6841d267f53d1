// SPDX-License-Identifier: Apache-2.0
// Tileable noise for procedural clouds, baked into small periodic 3D textures.
//
// Schneider 2015 ("The real-time volumetric cloudscapes of Horizon Zero Dawn", SIGGRAPH
// Advances in Real-Time Rendering; and GPU Pro 7, "Real-time volumetric cloudscapes")
// builds cloud shapes from two tiling 3D textures: a low-frequency one (a Perlin-Worley
// channel and three Worley octaves) that gives the base shape, and a high-frequency one
// (three Worley octaves) that erodes its edges into wisps and billows. Welkin bakes the
// same textures on the CPU at construction, from integer hashes and double arithmetic
// alone (no platform random generator, no transcendental functions), so they are the
// same bits on every machine for a given seed.
//
//  * Worley (cellular) noise, Worley 1996 ("A cellular texture basis function", SIGGRAPH):
//    one feature point per lattice cell, hashed from (seed, cell); the value is the
//    distance to the nearest feature point in cell units, inverted (1 - d, clamped) so
//    that cell centres are dense, as Schneider uses it ("billowy" shapes).
//  * Perlin gradient noise, Perlin 2002 ("Improving noise", SIGGRAPH): hashed gradients
//    from the 12 cube edge directions at lattice points, quintic fade 6t^5 - 15t^4 + 10t^3.
//  * Perlin-Worley: the Perlin fBm dilated by Worley, pw = worley + perlin (1 - worley),
//    Schneider's "remap(perlin, 0, 1, worley, 1)": connected, billowy base shapes.
// Tiling: every lattice is wrapped with a period equal to its frequency (an integer number
// of cells per texture), so every octave, and hence the texture, repeats over [0, 1)^3.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/vec4.hpp>

namespace welkin {

// Periodic noise on the unit cube at integer `frequency` (cells per unit), in [0, 1].
double tileable_worley(double x, double y, double z, int frequency, std::uint64_t seed);
double tileable_perlin(double x, double y, double z, int frequency, std::uint64_t seed);  // ~[-1, 1]

// An nx x ny x nz texture of four channels over [0, 1)^3 with wrap-around trilinear
// lookup (nz = 1: a 2D texture).
class TileableTexture3D {
public:
    TileableTexture3D() = default;
    TileableTexture3D(int nx, int ny, int nz)
        : nx_(nx), ny_(ny), nz_(nz), texels_(std::size_t(nx) * ny * nz) {}
    int size() const { return nx_; }
    glm::vec4& at(int i, int j, int k) { return texels_[(std::size_t(k) * ny_ + j) * nx_ + i]; }
    const glm::vec4& at(int i, int j, int k) const { return texels_[(std::size_t(k) * ny_ + j) * nx_ + i]; }
    // (x, y, z) in texture units (one period = 1), any real value; texel centres at (i + 0.5) / n.
    glm::vec4 sample(double x, double y, double z) const;

private:
    int nx_ = 0, ny_ = 0, nz_ = 0;
    std::vector<glm::vec4> texels_;
};

// A periodic n^3 (or n^2 x 1) texture of N float channels with the texel layout and
// wrap-around trilinear lookup of TileableTexture3D::sample (its texel coordinate taken in
// one step, not wrapped first: the two agree to rounding), for the few channels a density actually
// reads (ProceduralClouds keeps its noise's fixed linear combinations here: trilinear
// interpolation is linear, so interpolating the combination equals combining the
// interpolations). Smaller texels stay in the caches: the lookups are the march's cost.
template <int N>
class PeriodicTexture {
public:
    PeriodicTexture() = default;
    PeriodicTexture(int nx, int ny, int nz)
        : nx_(nx), ny_(ny), nz_(nz), texels_(std::size_t(nx) * ny * nz * N) {}
    float* at(int i, int j, int k) { return &texels_[((std::size_t(k) * ny_ + j) * nx_ + i) * N]; }
    const float* at(int i, int j, int k) const {
        return &texels_[((std::size_t(k) * ny_ + j) * nx_ + i) * N];
    }

    // (x, y, z) in texture units (one period = 1); out receives N values. Inlined: it is
    // most of a cloud density lookup.
    [[gnu::always_inline]] inline void sample(double x, double y, double z, float* out) const {
        // Per axis: texel centres at (i + 0.5) / n, so the lower texel is floor(u n - 0.5)
        // wrapped into [0, n): a mask for the power-of-two sizes the noise is baked at,
        // a modulo otherwise.
        const auto axis = [](double u, int n, int& i0, int& i1, float& w) {
            const double f = u * double(n) - 0.5;
            const double b = std::floor(f);
            w = float(f - b);
            const std::int64_t i = std::int64_t(b);
            if ((n & (n - 1)) == 0) {
                i0 = int(i & (n - 1));
                i1 = int((i + 1) & (n - 1));
            } else {
                i0 = int(((i % n) + n) % n);
                i1 = i0 + 1 == n ? 0 : i0 + 1;
            }
        };
        int i0, i1, j0, j1, k0 = 0, k1 = 0;
        float wx, wy, wz = 0.0f;
        axis(x, nx_, i0, i1, wx);
        axis(y, ny_, j0, j1, wy);
        if (nz_ > 1) axis(z, nz_, k0, k1, wz);
        const auto layer = [&](int k, float* v) {
            const float *a = at(i0, j0, k), *b = at(i1, j0, k), *c = at(i0, j1, k), *d = at(i1, j1, k);
            for (int q = 0; q < N; ++q) {
                const float lo = a[q] + wx * (b[q] - a[q]), hi = c[q] + wx * (d[q] - c[q]);
                v[q] = lo + wy * (hi - lo);
            }
        };
        layer(k0, out);
        if (nz_ == 1) return;
        float up[N];
        layer(k1, up);
        for (int q = 0; q < N; ++q) out[q] += wz * (up[q] - out[q]);
    }

private:
    int nx_ = 0, ny_ = 0, nz_ = 0;
    std::vector<float> texels_;
};

// Schneider's two textures and a weather texture, baked for one seed.
struct CloudNoiseTextures {
    // base: r = Perlin-Worley, g, b, a = Worley at 4, 8, 16 cells per period (size^3).
    // detail: r, g, b = Worley at 4, 8, 16 cells per period.
    // weather: a 2D map stored as an n x n x 1 texture: r = coverage variation, g = the
    // towers' height variation, b, a = a domain warp of the base shape (that breaks the
    // base texture's repetition), all Perlin fBm in [0, 1] (n x n x 1).
    // curl: a 2D divergence-free field (r, g in ~[-1, 1]), the curl of a Perlin fBm
    // potential psi, (d psi / dy, -d psi / dx) (Bridson et al. 2007, "Curl-noise for
    // procedural fluid flow", SIGGRAPH), that distorts the erosion noise as Schneider's
    // Nubis does (n x n x 1).
    TileableTexture3D base, detail, weather, curl;
    static CloudNoiseTextures bake(std::uint64_t seed, int base_size = 64, int detail_size = 32,
                                   int weather_size = 128, int curl_size = 64);
};

}  // namespace welkin
