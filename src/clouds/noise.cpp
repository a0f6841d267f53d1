// SPDX-License-Identifier: Apache-2.0
// Tileable cloud noise; see clouds/noise.hpp.
#include "welkin/clouds/noise.hpp"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/base/math.hpp"
#include "welkin/base/rng.hpp"

namespace welkin {
namespace {

std::uint64_t hash_cell(std::uint64_t seed, int i, int j, int k, std::uint64_t salt) {
    std::uint64_t h = splitmix64_mix(seed ^ (salt * 0x9e3779b97f4a7c15ULL));
    h = splitmix64_mix(h + std::uint64_t(std::uint32_t(i)));
    h = splitmix64_mix(h + (std::uint64_t(std::uint32_t(j)) << 21));
    return splitmix64_mix(h + (std::uint64_t(std::uint32_t(k)) << 42));
}

double unit_from_bits(std::uint64_t h, int shift) {
    return double((h >> shift) & 0xfffff) / double(0x100000);
}

double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// Perlin 2002's 12 gradient directions (cube edges).
constexpr int kGradients[12][3] = {{1, 1, 0},  {-1, 1, 0},  {1, -1, 0}, {-1, -1, 0}, {1, 0, 1},  {-1, 0, 1},
                                   {1, 0, -1}, {-1, 0, -1}, {0, 1, 1},  {0, -1, 1},  {0, 1, -1}, {0, -1, -1}};

// The feature points of one Worley lattice (frequency f, seed) and the gradients of one
// Perlin lattice, hashed once per cell: a texel of the bake reads 27 cells per Worley
// octave and 8 per Perlin octave, and the hashes were most of its cost. The distances and
// the interpolation are the same arithmetic, on the same doubles, as the functions below:
// the same bits.
class WorleyLattice {
public:
    WorleyLattice(int f, std::uint64_t seed) : f_(f), p_(std::size_t(f) * f * f * 3) {
        for (int k = 0; k < f; ++k)
            for (int j = 0; j < f; ++j)
                for (int i = 0; i < f; ++i) {
                    const std::uint64_t h = hash_cell(seed, i, j, k, 1);
                    double* q = &p_[((std::size_t(k) * f + j) * f + i) * 3];
                    q[0] = unit_from_bits(h, 0), q[1] = unit_from_bits(h, 20), q[2] = unit_from_bits(h, 40);
                }
    }
    double operator()(double x, double y, double z) const {
        const int f = f_;
        const double px = x * f, py = y * f, pz = z * f;
        const int ci = int(std::floor(px)), cj = int(std::floor(py)), ck = int(std::floor(pz));
        double best = 1e30;
        for (int dk = -1; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) {
                    const int i = ci + di, j = cj + dj, k = ck + dk;
                    const double* q =
                        &p_[((std::size_t(wrap_index(k, f)) * f + std::size_t(wrap_index(j, f))) * f +
                             std::size_t(wrap_index(i, f))) *
                            3];
                    const double fx = i + q[0] - px;
                    const double fy = j + q[1] - py;
                    const double fz = k + q[2] - pz;
                    best = std::min(best, fx * fx + fy * fy + fz * fz);
                }
        return std::clamp(1.0 - best, 0.0, 1.0);
    }

private:
    int f_;
    std::vector<double> p_;
};

class PerlinLattice {
public:
    PerlinLattice(int f, std::uint64_t seed) : f_(f), g_(std::size_t(f) * f * f) {
        for (int k = 0; k < f; ++k)
            for (int j = 0; j < f; ++j)
                for (int i = 0; i < f; ++i)
                    g_[(std::size_t(k) * f + j) * f + i] = std::uint8_t(hash_cell(seed, i, j, k, 2) % 12);
    }
    double operator()(double x, double y, double z) const {
        const int f = f_;
        const double px = x * f, py = y * f, pz = z * f;
        const int ci = int(std::floor(px)), cj = int(std::floor(py)), ck = int(std::floor(pz));
        const double tx = px - ci, ty = py - cj, tz = pz - ck;
        double corner[8];
        for (int c = 0; c < 8; ++c) {
            const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
            const int* g = kGradients
                [g_[(std::size_t(wrap_index(ck + dk, f)) * f + std::size_t(wrap_index(cj + dj, f))) * f +
                    std::size_t(wrap_index(ci + di, f))]];
            corner[c] = g[0] * (tx - di) + g[1] * (ty - dj) + g[2] * (tz - dk);
        }
        return interpolate(corner, tx, ty, tz);
    }
    static double interpolate(const double corner[8], double tx, double ty, double tz) {
        const double u = fade(tx), v = fade(ty), w = fade(tz);
        const auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
        const double x00 = lerp(corner[0], corner[1], u), x10 = lerp(corner[2], corner[3], u);
        const double x01 = lerp(corner[4], corner[5], u), x11 = lerp(corner[6], corner[7], u);
        return lerp(lerp(x00, x10, v), lerp(x01, x11, v), w);
    }

private:
    int f_;
    std::vector<std::uint8_t> g_;
};

}  // namespace

double tileable_worley(double x, double y, double z, int f, std::uint64_t seed) {
    const double px = x * f, py = y * f, pz = z * f;
    const int ci = int(std::floor(px)), cj = int(std::floor(py)), ck = int(std::floor(pz));
    double best = 1e30;
    for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
                const int i = ci + di, j = cj + dj, k = ck + dk;
                const std::uint64_t h =
                    hash_cell(seed, wrap_index(i, f), wrap_index(j, f), wrap_index(k, f), 1);
                const double fx = i + unit_from_bits(h, 0) - px;
                const double fy = j + unit_from_bits(h, 20) - py;
                const double fz = k + unit_from_bits(h, 40) - pz;
                best = std::min(best, fx * fx + fy * fy + fz * fz);
            }
    return std::clamp(1.0 - best, 0.0, 1.0);
}

double tileable_perlin(double x, double y, double z, int f, std::uint64_t seed) {
    const double px = x * f, py = y * f, pz = z * f;
    const int ci = int(std::floor(px)), cj = int(std::floor(py)), ck = int(std::floor(pz));
    const double tx = px - ci, ty = py - cj, tz = pz - ck;
    double corner[8];
    for (int c = 0; c < 8; ++c) {
        const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
        const std::uint64_t h =
            hash_cell(seed, wrap_index(ci + di, f), wrap_index(cj + dj, f), wrap_index(ck + dk, f), 2);
        const int* g = kGradients[h % 12];
        corner[c] = g[0] * (tx - di) + g[1] * (ty - dj) + g[2] * (tz - dk);
    }
    return PerlinLattice::interpolate(corner, tx, ty, tz);
}

glm::vec4 TileableTexture3D::sample(double x, double y, double z) const {
    // Per axis: wrap to one period (u - floor(u) in [0, 1]), then texel centres at
    // (i + 0.5) / n: the lower texel is floor(u n - 0.5), in [-1, n - 1] (-1 wraps to
    // n - 1, and a rounding of u - floor(u) up to 1 gives n - 1 as well).
    const auto axis = [](double u, int n, int& i0, int& i1, float& w) {
        const double f = (u - std::floor(u)) * n - 0.5;
        const double b = std::floor(f);
        w = float(f - b);
        int i = int(b);
        if (i < 0) i += n;
        if (i >= n) i = n - 1;
        i0 = i;
        i1 = i + 1 == n ? 0 : i + 1;
    };
    int i0, i1, j0, j1, k0 = 0, k1 = 0;
    float wx, wy, wz = 0.0f;
    axis(x, nx_, i0, i1, wx);
    axis(y, ny_, j0, j1, wy);
    if (nz_ > 1) axis(z, nz_, k0, k1, wz);  // a 2D texture (nz = 1): every z reads the one layer
    const auto layer = [&](int k) {
        return glm::mix(glm::mix(at(i0, j0, k), at(i1, j0, k), wx),
                        glm::mix(at(i0, j1, k), at(i1, j1, k), wx), wy);
    };
    const glm::vec4 lo = layer(k0);
    if (nz_ == 1) return lo;
    return glm::mix(lo, layer(k1), wz);
}

CloudNoiseTextures CloudNoiseTextures::bake(std::uint64_t seed, int base_size, int detail_size,
                                            int weather_size, int curl_size) {
    CloudNoiseTextures t{TileableTexture3D(base_size, base_size, base_size),
                         TileableTexture3D(detail_size, detail_size, detail_size),
                         TileableTexture3D(weather_size, weather_size, 1),
                         TileableTexture3D(curl_size, curl_size, 1)};
    // Perlin fBm: octaves of doubling frequency and halving amplitude (4, 8, 16 cells),
    // mapped from ~[-1, 1] to [0, 1]; Worley fBm: octaves f0, 2 f0, 4 f0 weighted 0.625,
    // 0.25, 0.125. Each octave's lattice hashed once (above).
    struct PerlinFbm {
        std::vector<PerlinLattice> octaves;
        PerlinFbm(int f0, std::uint64_t s) {
            for (int o = 0; o < 3; ++o) octaves.emplace_back(f0 << o, s + std::uint64_t(o));
        }
        double operator()(double x, double y, double z) const {
            double sum = 0.0, amp = 0.5, norm = 0.0;
            for (int o = 0; o < 3; ++o, amp *= 0.5) {
                sum += amp * octaves[std::size_t(o)](x, y, z);
                norm += amp;
            }
            return std::clamp(0.5 + 0.5 * sum / norm * 1.4, 0.0, 1.0);  // 1.4: Perlin rarely reaches +-1
        }
    };
    struct WorleyFbm {
        WorleyLattice a, b, c;
        WorleyFbm(int f0, std::uint64_t s) : a(f0, s), b(2 * f0, s + 1), c(4 * f0, s + 2) {}
        double operator()(double x, double y, double z) const {
            return 0.625 * a(x, y, z) + 0.25 * b(x, y, z) + 0.125 * c(x, y, z);
        }
    };
    const int nb = base_size;
    {
        const WorleyFbm shape(4, seed * 16 + 1), w4(4, seed * 16 + 8), w8(8, seed * 16 + 11),
            w16(16, seed * 16 + 14);
        const PerlinFbm perlin_fbm(4, seed * 16 + 5);
        tbb::parallel_for(tbb::blocked_range<int>(0, nb), [&](const auto& r) {
            for (int k = r.begin(); k != r.end(); ++k)
                for (int j = 0; j < nb; ++j)
                    for (int i = 0; i < nb; ++i) {
                        const double x = (i + 0.5) / nb, y = (j + 0.5) / nb, z = (k + 0.5) / nb;
                        const double worley = shape(x, y, z);
                        const double perlin = perlin_fbm(x, y, z);
                        t.base.at(i, j, k) =
                            glm::vec4(float(worley + perlin * (1.0 - worley)), float(w4(x, y, z)),
                                      float(w8(x, y, z)), float(w16(x, y, z)));
                    }
        });
    }
    const int nd = detail_size;
    {
        const WorleyFbm w4(4, seed * 16 + 3), w8(8, seed * 16 + 6), w16(16, seed * 16 + 9);
        tbb::parallel_for(tbb::blocked_range<int>(0, nd), [&](const auto& r) {
            for (int k = r.begin(); k != r.end(); ++k)
                for (int j = 0; j < nd; ++j)
                    for (int i = 0; i < nd; ++i) {
                        const double x = (i + 0.5) / nd, y = (j + 0.5) / nd, z = (k + 0.5) / nd;
                        t.detail.at(i, j, k) =
                            glm::vec4(float(w4(x, y, z)), float(w8(x, y, z)), float(w16(x, y, z)), 0.0f);
                    }
        });
    }
    // The weather map is 2D: an n x n x 1 texture.
    const int nw = weather_size;
    {
        const PerlinFbm wr(2, seed * 16 + 20), wg(2, seed * 16 + 24), wb(4, seed * 16 + 28),
            wa(4, seed * 16 + 32);
        tbb::parallel_for(tbb::blocked_range<int>(0, nw), [&](const auto& r) {
            for (int j = r.begin(); j != r.end(); ++j)
                for (int i = 0; i < nw; ++i) {
                    const double x = (i + 0.5) / nw, y = (j + 0.5) / nw, z = 0.5 / nw;
                    t.weather.at(i, j, 0) = glm::vec4(float(wr(x, y, z)), float(wg(x, y, z)),
                                                      float(wb(x, y, z)), float(wa(x, y, z)));
                }
        });
    }
    // Curl noise: psi a Perlin fBm at 4 cells per period, differentiated by central
    // differences of half a texel; scaled so that |curl| is about 1 at its largest.
    const int nc = curl_size;
    const double hd = 0.5 / nc;
    const PerlinFbm psi_fbm(4, seed * 16 + 36);
    tbb::parallel_for(tbb::blocked_range<int>(0, nc), [&](const auto& r) {
        for (int j = r.begin(); j != r.end(); ++j)
            for (int i = 0; i < nc; ++i) {
                const double x = (i + 0.5) / nc, y = (j + 0.5) / nc;
                const auto psi = [&](double u, double v) { return psi_fbm(u, v, 0.25); };
                const double dx = (psi(x + hd, y) - psi(x - hd, y)) / (2.0 * hd);
                const double dy = (psi(x, y + hd) - psi(x, y - hd)) / (2.0 * hd);
                // psi's slope is of order (cells per period) x (amplitude): 4 x 0.7 / 2.
                constexpr double kScale = 1.0 / 1.4 / 4.0;
                t.curl.at(i, j, 0) = glm::vec4(float(dy * kScale), float(-dx * kScale), 0.0f, 0.0f);
            }
    });
    return t;
}

}  // namespace welkin
