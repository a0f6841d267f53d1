// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/transmittance_lut.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/geometry.hpp"

namespace welkin {
namespace {

// 4-point Gauss-Legendre on [0, 1] (nodes (1 +- x)/2, weights w/2; A&S table 25.4).
constexpr std::array<double, 4> kGlNodes = {0.5 - 0.5 * 0.8611363115940526, 0.5 - 0.5 * 0.3399810435848563,
                                            0.5 + 0.5 * 0.3399810435848563, 0.5 + 0.5 * 0.8611363115940526};
constexpr std::array<double, 4> kGlWeights = {0.5 * 0.3478548451374538, 0.5 * 0.6521451548625461,
                                              0.5 * 0.6521451548625461, 0.5 * 0.3478548451374538};

// At most this many breakpoint radii are cut at (each crossed at most once by a piece,
// which is monotone in altitude; twice counted for safety); more are left uncut.
constexpr int ColumnCutLimit = 16;

}  // namespace

// Integral of extinction over [a, b] of the ray, densest at `a` (toward_a) or `b`.
// Substituting t = a + (b - a) s^2 (or the mirror image) clusters samples at the dense
// end; the integrand in s, rho(t(s)) 2 (b - a) s, is smooth, so composite Gauss-Legendre
// in s converges fast. A piece keeps its nodes' s^2 and weights w 2 s / panels (the
// factor b - a is applied to the sum); each block of samples is one pass computing the
// squared radii (in double; it vectorises) and their table entries, and one fetching the
// extinction.
GradedQuadrature::Piece GradedQuadrature::make_piece(int panels) {
    Piece piece;
    for (int p = 0; p < panels; ++p)
        for (int k = 0; k < 4; ++k) {
            const double s = (double(p) + kGlNodes[k]) / double(panels);
            piece.s2.push_back(s * s);
            piece.weight.push_back(float(kGlWeights[k] * 2.0 * s / double(panels)));
        }
    return piece;
}

GradedQuadrature::GradedQuadrature(int samples)
    : whole_(make_piece(std::max(1, samples / 4))), half_(make_piece(std::max(1, samples / 8))) {}

namespace {

// The arithmetic pass over a block of nodes: the table coordinate of each node's radius,
// clamped to the table, as an entry and a weight (AtmosphereBatch::extinction_at). The
// table is uniform in r^2 - R^2 = (t + r mu)^2 + c with c = r^2 (1 - mu^2) - R^2 formed once
// per ray: a multiply-add per node, no square root.
WELKIN_SIMD_CLONES void table_coordinates(double r_mu, double c, double inv_step, double origin,
                                          double direction, double x_max, const double* __restrict s2,
                                          std::size_t m, int* __restrict entry, float* __restrict fraction) {
    for (std::size_t l = 0; l < m; ++l) {
        const double t_low = origin + direction * s2[l] + r_mu;  // t + r mu
        const double x = min_value(max_value((t_low * t_low + c) * inv_step, 0.0), x_max);
        const int i = int(x);
        entry[l] = i;
        fraction[l] = float(x - double(i));
    }
}

}  // namespace

// Where a density profile has a kink (the ozone tent's 10, 25 and 40 km), the integrand is
// only continuous, and a panel across the kink converges like the midpoint rule, not like
// Gauss-Legendre: with 40 nodes and no cuts, up to 0.024 in tau (2.4 % in T) on grazing
// rays through the tent, against 4e-6 for an atmosphere without kinks (mars). So the ray's crossings of
// the batch's breakpoint radii inside [a, b], at (t + r mu)^2 = r_b^2 - r^2 (1 - mu^2),
// cut the substitution's s axis: a panel holding a crossing is split there into
// Gauss-Legendre sub-panels, so every panel integrates a smooth function, and the other
// panels keep their precomputed nodes.
// Rays crossing no breakpoint use the precomputed piece.
Spectrum4 GradedQuadrature::integrate(const AtmosphereBatch& batch, double r, double mu, double a, double b,
                                      bool toward_a, const Piece& piece) const {
    const double len = b - a;
    if (!(len > 0.0)) return Spectrum4(0.0f);
    const double origin = toward_a ? a : b, direction = toward_a ? len : -len;
    const double r_mu = r * mu, r_sin2 = r * r * std::max((1.0 - mu) * (1.0 + mu), 0.0);
    const double x_max = double(AtmosphereBatch::kTableSize - 1);
    const double R = batch.bottom_radius(), c = r_sin2 - R * R;
    constexpr std::size_t kBlock = 64;
    // Two partial sums (even and odd nodes), so that consecutive nodes' additions do not
    // wait on each other.
    Float4 sum = {0.0f, 0.0f, 0.0f, 0.0f}, sum_odd = sum;
    auto accumulate = [&](const double* s2, const float* weight, std::size_t n) {
        int entry[kBlock];
        float fraction[kBlock];
        for (std::size_t first = 0; first < n; first += kBlock) {
            const std::size_t m = std::min(kBlock, n - first);
            table_coordinates(r_mu, c, batch.inv_table_step(), origin, direction, x_max, s2 + first, m, entry,
                              fraction);
            const float* const w = weight + first;
            std::size_t l = 0;
            for (; l + 1 < m; l += 2) {
                sum += w[l] * batch.extinction_at(entry[l], fraction[l]);
                sum_odd += w[l + 1] * batch.extinction_at(entry[l + 1], fraction[l + 1]);
            }
            if (l < m) sum += w[l] * batch.extinction_at(entry[l], fraction[l]);
        }
    };
    // The crossings, as s = sqrt((t - origin) / direction) in (0, 1).
    constexpr int kMaxCuts = 2 * ColumnCutLimit;
    double cuts[kMaxCuts];
    int n_cuts = 0;
    // [a, b] never contains the tangent point inside it, so its radius is monotone and each
    // breakpoint between its end radii is crossed once: on the far side of the tangent
    // (rising) at t = -r mu + q, on the near side at -r mu - q, q^2 = r_b^2 - r^2 sin^2.
    const double ta = a + r_mu, tb = b + r_mu;  // t + r mu at both ends
    const double ra2 = ta * ta + r_sin2, rb2 = tb * tb + r_sin2;
    const double lo2 = std::min(ra2, rb2), hi2 = std::max(ra2, rb2);
    const bool rising = ta + tb > 0.0;
    for (double rb : batch.breakpoint_radii()) {
        const double rb2_k = rb * rb;
        if (!(rb2_k > lo2 && rb2_k < hi2) || n_cuts == kMaxCuts) continue;
        const double q = std::sqrt(rb2_k - r_sin2);
        const double t = rising ? q - r_mu : -q - r_mu;
        cuts[n_cuts++] = std::sqrt(std::clamp((t - origin) / direction, 0.0, 1.0));
    }
    if (n_cuts == 0) {
        accumulate(piece.s2.data(), piece.weight.data(), piece.s2.size());
        return to_vec4((sum + sum_odd) * float(len));
    }
    std::sort(cuts, cuts + n_cuts);
    // Panels without a cut keep the piece's nodes; a panel with cuts is split at them into
    // sub-panels of the piece's four Gauss-Legendre nodes each. A ray crossing k breakpoints
    // so costs 4k nodes more than an uncut one, and only those panels' nodes are made here.
    const int panels = int(piece.s2.size() / 4);
    constexpr int kStackNodes = 512;
    double s2_stack[kStackNodes];
    float weight_stack[kStackNodes];
    std::vector<double> s2_heap;
    std::vector<float> weight_heap;
    double* s2 = s2_stack;
    float* weight = weight_stack;
    const std::size_t most = piece.s2.size() + std::size_t(4 * n_cuts);
    if (most > std::size_t(kStackNodes)) {
        s2_heap.resize(most);
        weight_heap.resize(most);
        s2 = s2_heap.data();
        weight = weight_heap.data();
    }
    std::size_t n = 0;
    int next_cut = 0;
    for (int p = 0; p < panels; ++p) {
        const double u0 = double(p) / double(panels), u1 = double(p + 1) / double(panels);
        if (next_cut >= n_cuts || cuts[next_cut] >= u1) {
            for (int k = 0; k < 4; ++k, ++n) {
                s2[n] = piece.s2[std::size_t(4 * p + k)];
                weight[n] = piece.weight[std::size_t(4 * p + k)];
            }
            continue;
        }
        double lo = u0;
        for (;;) {
            const bool cut_here = next_cut < n_cuts && cuts[next_cut] < u1;
            const double hi = cut_here ? cuts[next_cut] : u1;
            if (cut_here) ++next_cut;
            const double h = hi - lo;
            if (h > 0.0)
                for (int k = 0; k < 4; ++k, ++n) {
                    const double x = lo + h * kGlNodes[std::size_t(k)];
                    s2[n] = x * x;
                    weight[n] = float(kGlWeights[std::size_t(k)] * 2.0 * x * h);
                }
            lo = hi;
            if (!cut_here) break;
        }
    }
    accumulate(s2, weight, n);
    return to_vec4((sum + sum_odd) * float(len));
}

Spectrum4 GradedQuadrature::optical_depth(const AtmosphereBatch& batch, double r, double mu,
                                          double length) const {
    const double t_low = -r * mu;  // the ray's lowest point, when it lies ahead
    if (t_low <= 0.0) return integrate(batch, r, mu, 0.0, length, true, whole_);
    if (t_low >= length) return integrate(batch, r, mu, 0.0, length, false, whole_);
    return integrate(batch, r, mu, 0.0, t_low, false, half_) +
           integrate(batch, r, mu, t_low, length, true, half_);
}

Spectrum4 march_optical_depth(const AtmosphereBatch& batch, double r, double mu, double length, int samples) {
    return GradedQuadrature(samples).optical_depth(batch, r, mu, length);
}

TransmittanceLut::TransmittanceLut(const AtmosphereBatch& batch, int width, int height, int steps)
    : bottom_(batch.bottom_radius()),
      top_(batch.top_radius()),
      H_(std::sqrt((top_ - bottom_) * (top_ + bottom_))),
      sun_angular_radius_(batch.sun_angular_radius()),
      texture_(width, height) {
    const GradedQuadrature quadrature(steps);
    tbb::parallel_for(0, height, [&](int j) {
        // r_mu_from_uv, with the parts that depend on the row alone formed once.
        const double H = H_;
        const double rho = H * double(unit_from_texcoord((float(j) + 0.5f) / float(height), height));
        const double r = std::sqrt(rho * rho + bottom_ * bottom_);
        const double d_min = top_ - r, d_max = rho + H;
        for (int i = 0; i < width; ++i) {
            const double x_mu = unit_from_texcoord((float(i) + 0.5f) / float(width), width);
            const double d = d_min + x_mu * (d_max - d_min);
            const double mu = d == 0.0 ? 1.0 : clamp_cosine((H * H - rho * rho - d * d) / (2.0 * r * d));
            const Spectrum4 tau = quadrature.optical_depth(batch, r, mu, distance_to_top(r, mu, top_));
            texture_.at(i, j) = to_vec4(exp_nonpositive(-to_float4(tau)));
        }
    });
}

void TransmittanceLut::uv_from_r_mu(double r, double mu, float& u, float& v) const {
    uv_from_r_rho_mu(r, safe_sqrt((r - bottom_) * (r + bottom_)), mu, u, v);
}

void TransmittanceLut::r_mu_from_uv(float u, float v, double& r, double& mu) const {
    const double x_mu = unit_from_texcoord(u, texture_.width());
    const double x_r = unit_from_texcoord(v, texture_.height());
    const double H = H_;
    const double rho = H * x_r;
    r = std::sqrt(rho * rho + bottom_ * bottom_);
    const double d_min = top_ - r, d_max = rho + H;
    const double d = d_min + x_mu * (d_max - d_min);
    // Invert d = -r mu + sqrt(r^2 mu^2 - r^2 + top^2) for mu.
    mu = d == 0.0 ? 1.0 : clamp_cosine((H * H - rho * rho - d * d) / (2.0 * r * d));
}

Spectrum4 TransmittanceLut::to_top(double r, double mu) const {
    float u, v;
    uv_from_r_mu(std::min(r, top_), mu, u, v);
    return texture_.sample(u, v);
}

TransmittanceLut::AtRadius TransmittanceLut::at_radius(double r_in) const {
    AtRadius a;
    a.r = std::min(r_in, top_);
    a.r_f = float(a.r);
    a.top_k = float(std::max((top_ - a.r) * (top_ + a.r), 0.0));
    const double rho = safe_sqrt((a.r - bottom_) * (a.r + bottom_));
    const double d_min = top_ - a.r;
    a.d_min = float(d_min);
    const double range = rho + H_ - d_min;
    a.x_scale = range > 0.0 ? float(double(texture_.width() - 1) / range) : 0.0f;
    // sun_visible_fraction's smoothstep argument (mu_s - cos_h + alpha) / (2 alpha).
    const double cos_h = horizon_cosine(a.r, rho);
    const double alpha = sun_angular_radius_;
    a.fraction_scale = float(1.0 / (2.0 * alpha));
    a.fraction_offset = float((alpha - cos_h) / (2.0 * alpha));
    a.row = texture_.row(texcoord_from_unit(float(clamp01(rho / H_)), texture_.height()));
    return a;
}

}  // namespace welkin
