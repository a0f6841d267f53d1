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
//    distance d to the nearest feature point in cell units, inverted as 1 - d^2 (clamped) so
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
#include <cstring>
#include <vector>

#include <glm/vec4.hpp>

#include "welkin/base/math.hpp"
#include "welkin/base/simd.hpp"

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
    static_assert(N >= 1 && N <= 4, "a texel is read as one Float4");

public:
    PeriodicTexture() = default;
    // 4 - N floats after the last texel, so that every texel is read four floats at a time
    // (sample) inside the buffer.
    PeriodicTexture(int nx, int ny, int nz)
        : nx_(nx),
          ny_(ny),
          nz_(nz),
          mask_x_(wrap_mask(nx)),
          mask_y_(wrap_mask(ny)),
          mask_z_(wrap_mask(nz)),
          texels_(std::size_t(nx) * ny * nz * N + (4 - N)) {}
    float* at(int i, int j, int k) { return &texels_[((std::size_t(k) * ny_ + j) * nx_ + i) * N]; }
    const float* at(int i, int j, int k) const {
        return &texels_[((std::size_t(k) * ny_ + j) * nx_ + i) * N];
    }

    // (x, y, z) in texture units (one period = 1); out receives N values. Inlined: it is
    // most of a cloud density lookup.
    [[gnu::always_inline]] inline void sample(double x, double y, double z, float* out) const {
        int i0, i1, j0, j1, k0 = 0, k1 = 0;
        float wx, wy, wz = 0.0f;
        axis(x, nx_, mask_x_, i0, i1, wx);
        axis(y, ny_, mask_y_, j0, j1, wy);
        if (nz_ > 1) axis(z, nz_, mask_z_, k0, k1, wz);
        // The N channels as one Float4 (the lanes past N are the next texel's channels, or the
        // padding: read, never stored): per lane the float operations of a scalar trilinear
        // lookup, so its bits.
        const auto layer = [&](int k) {
            const Float4 a = load4(at(i0, j0, k)), b = load4(at(i1, j0, k));
            const Float4 c = load4(at(i0, j1, k)), d = load4(at(i1, j1, k));
            const Float4 lo = a + wx * (b - a), hi = c + wx * (d - c);
            return lo + wy * (hi - lo);
        };
        Float4 v = layer(k0);
        if (nz_ > 1) {
            const Float4 up = layer(k1);
            v = v + wz * (up - v);
        }
        for (int q = 0; q < N; ++q) out[q] = v[q];
    }

private:
    // n - 1 for a power-of-two size (the sizes the noise is baked at: the wrap is a mask),
    // -1 otherwise (a modulo).
    static int wrap_mask(int n) { return n > 0 && (n & (n - 1)) == 0 ? n - 1 : -1; }
    // One axis: texel centres at (i + 0.5) / n, so the lower texel is floor(u n - 0.5)
    // wrapped into [0, n).
    [[gnu::always_inline]] static void axis(double u, int n, int mask, int& i0, int& i1, float& w) {
        const double f = u * double(n) - 0.5;
        const std::int64_t i = floor_to_int64(f);
        w = float(f - double(i));
        if (mask >= 0) {
            i0 = int(i & mask);
            i1 = int((i + 1) & mask);
        } else {
            i0 = int(((i % n) + n) % n);
            i1 = i0 + 1 == n ? 0 : i0 + 1;
        }
    }
    static Float4 load4(const float* p) {
        Float4 v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }

    int nx_ = 0, ny_ = 0, nz_ = 0;
    int mask_x_ = -1, mask_y_ = -1, mask_z_ = -1;
    std::vector<float> texels_;
};

// Aperiodic lookups of a periodic texture by hex tiling (Heitz & Neyret 2018, "High-performance
// by-example noise using a histogram-preserving blending operator", Proc. ACM CGIT 1(2);
// Mikkelsen 2022, "Practical real-time hex-tiling", JCGT 11(2)). The texture plane is covered by
// a triangular lattice of vertices `cell` texture units apart; each vertex reads the texture
// shifted by an offset of its own (a hash of the vertex and the seed, uniform over one period),
// and a point blends the reads of its triangle's three vertices, each weighted by its
// barycentric coordinate (a tent over the vertex's hexagon, zero on the far edge: the blend is
// continuous) raised to kHexSharpness, normalised, less kHexCutoff (a weight that reaches 0
// continuously, so that half the plane needs one read and most of the rest two: 1.6 reads on
// average, 8 % of the plane three), renormalised.
// With cell <= 1/2 two points a whole period apart never share a vertex, so they read unrelated
// parts of the texture: the field no longer repeats at the texture's period or its multiples
// (a wrapped texture alone repeats, and seen over tens of periods from above the repetition
// reads as ribbing). The blend keeps the texture's contrast (Heitz & Neyret, sec. 3.2, the
// variance-preserving blend): mean + sum_i w_i (read_i - mean) / sqrt(sum_i w_i^2).
struct HexTaps {
    static constexpr double kHexSharpness = 3.0, kHexCutoff = 0.1;
    // Left uninitialised (hex_taps sets count, contrast and the first count entries): the
    // taps are made once per read of a density lookup.
    int count;
    double du[3], dv[3];  // the reads' offsets, texture units
    double weight[3];     // sharpened, cut off, summing to 1
    double contrast;      // 1 / sqrt(sum weight^2): the variance-preserving factor
};
// The taps at texture coordinates (u, v): lattice spacing `cell` (texture units), offsets from
// `seed`.
inline void hex_taps(double u, double v, double cell, std::uint64_t seed, HexTaps& taps) {
    // Skewed coordinates (a, b) of the point on the lattice basis (cell, 0), (cell/2, cell sqrt(3)/2).
    constexpr double kInvSin60 = 1.1547005383792515;  // 2 / sqrt(3)
    const double b = v / cell * kInvSin60, a = u / cell - 0.5 * b;
    const std::int64_t i = floor_to_int64(a), j = floor_to_int64(b);
    const double ta = a - double(i), tb = b - double(j);
    std::int64_t vi[3], vj[3];
    double w[3];
    if (ta + tb < 1.0) {  // the lower triangle (i, j), (i + 1, j), (i, j + 1)
        vi[0] = i, vj[0] = j, w[0] = 1.0 - ta - tb;
        vi[1] = i + 1, vj[1] = j, w[1] = ta;
        vi[2] = i, vj[2] = j + 1, w[2] = tb;
    } else {  // the upper one (i + 1, j + 1), (i, j + 1), (i + 1, j)
        vi[0] = i + 1, vj[0] = j + 1, w[0] = ta + tb - 1.0;
        vi[1] = i, vj[1] = j + 1, w[1] = 1.0 - ta;
        vi[2] = i + 1, vj[2] = j, w[2] = 1.0 - tb;
    }
    double sum = 0.0;
    for (int k = 0; k < 3; ++k) {
        w[k] = w[k] * w[k] * w[k];  // kHexSharpness
        sum += w[k];
    }
    // One division per normalisation: the weights over their sum, less the cut-off, over
    // their sum K once cut; the contrast 1 / sqrt(sum (w_i / K)^2) = K / sqrt(sum w_i^2).
    const double inv_sum = 1.0 / sum;
    taps.count = 0;
    double kept = 0.0, sq = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double wk = w[k] * inv_sum - HexTaps::kHexCutoff;  // the largest is at least 1/3: one is kept
        if (wk <= 0.0) continue;
        // splitmix64's finaliser (base/rng.hpp's splitmix64_mix) of the vertex and the seed.
        std::uint64_t h = seed + 0x9e3779b97f4a7c15ULL * std::uint64_t(vi[k]) +
                          0xc2b2ae3d27d4eb4fULL * std::uint64_t(vj[k]);
        h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
        h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
        h ^= h >> 31;
        taps.du[taps.count] = double(h >> 40) / double(1 << 24);
        taps.dv[taps.count] = double((h >> 16) & 0xffffff) / double(1 << 24);
        taps.weight[taps.count] = wk;
        kept += wk;
        sq += wk * wk;
        ++taps.count;
    }
    const double inv_kept = 1.0 / kept;
    for (int k = 0; k < taps.count; ++k) taps.weight[k] *= inv_kept;
    taps.contrast = kept / std::sqrt(sq);
}

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
