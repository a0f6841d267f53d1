// SPDX-License-Identifier: Apache-2.0
// Column densities for the reference path tracer; see the header for the two kinds of
// constituent, the table's parametrisation and storage, and the accuracy.
#include "welkin/atmosphere/column_table.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/base/error.hpp"

namespace welkin {
namespace {

// 4-point Lagrange interpolation stencil for coordinate x in [0, 1] on n nodes: first
// node index and weights. Exact for cubics; the stencil moves inwards at the edges.
struct Stencil {
    int first;
    std::array<double, 4> w;
};

inline Stencil stencil(double x, int n) {
    const double u = std::clamp(x, 0.0, 1.0) * double(n - 1);
    const int i0 = std::clamp(int(std::floor(u)) - 1, 0, n - 4);
    const double f = u - double(i0);
    return {i0,
            {-(f - 1.0) * (f - 2.0) * (f - 3.0) / 6.0, f * (f - 2.0) * (f - 3.0) / 2.0,
             -f * (f - 1.0) * (f - 3.0) / 2.0, f * (f - 1.0) * (f - 2.0) / 6.0}};
}

// Primitive of the distance to the planet centre along a ray, in u = s + r mu with
// q = r sqrt(1 - mu^2): int sqrt(u^2 + q^2) du (see the header).
// asinh(u / q) = sign(u) ln((|u| + root) / q): one logarithm of an argument >= 1, free of
// cancellation.
inline double distance_primitive(double u, double q) {
    const double root = std::sqrt(u * u + q * q);
    if (!(q > 0.0)) return 0.5 * u * root;
    return 0.5 * (u * root + q * q * std::copysign(std::log((std::abs(u) + root) / q), u));
}

bool same_profile(const DensityProfile& a, const DensityProfile& b) {
    const auto& la = a.layers();
    const auto& lb = b.layers();
    if (la.size() != lb.size()) return false;
    for (std::size_t i = 0; i < la.size(); ++i)
        if (la[i].width_m != lb[i].width_m || la[i].exp_term != lb[i].exp_term ||
            la[i].exp_scale_per_m != lb[i].exp_scale_per_m || la[i].linear_per_m != lb[i].linear_per_m ||
            la[i].constant != lb[i].constant)
            return false;
    return true;
}

bool same_geometry(const Atmosphere& a, const Atmosphere& b) {
    return a.bottom_radius_m == b.bottom_radius_m && a.top_radius_m == b.top_radius_m &&
           same_profile(a.rayleigh_density, b.rayleigh_density) &&
           same_profile(a.mie_density, b.mie_density) &&
           same_profile(a.absorption_density, b.absorption_density);
}

}  // namespace

ColumnTable::ColumnTable(const Atmosphere& atm, int n_r, int n_mu)
    : bottom_(atm.bottom_radius_m),
      top_(atm.top_radius_m),
      H_(std::sqrt((atm.top_radius_m - atm.bottom_radius_m) * (atm.top_radius_m + atm.bottom_radius_m))),
      n_r_(n_r),
      n_mu_(n_mu),
      profiles_{atm.rayleigh_density, atm.mie_density, atm.absorption_density} {
    require_in_range("column_table.n_r", n_r, 8, 1 << 14);
    require_in_range("column_table.n_mu", n_mu, 8, 1 << 14);
    bool any_table = false;
    for (int k = 0; k < 3; ++k) {
        const DensityProfile& p = profiles_[std::size_t(k)];
        breakpoints_[k] = p.breakpoints_m();
        bool linear = int(breakpoints_[k].size()) <= kMaxBreakpoints, zero = true;
        for (const DensityLayer& l : p.layers()) {
            linear = linear && l.exp_term == 0.0;
            zero = zero && l.exp_term == 0.0 && l.linear_per_m == 0.0 && l.constant <= 0.0;
        }
        kind_[k] = zero ? Kind::Zero : linear ? Kind::Linear : Kind::Table;
        log_offset_[k] = 0.0;
        if (kind_[k] == Kind::Table) {
            any_table = true;
            if (const auto hs = p.exponential_scale_height_m())
                log_offset_[k] = std::max(1e-3, 30.0 * *hs * p.density(top_ - bottom_));
        }
    }
    if (!any_table) return;
    for (int k = 0; k < 3; ++k)
        if (kind_[k] == Kind::Table) table_slot_[n_table_++] = k;
    values_.assign(std::size_t(n_r) * std::size_t(n_mu) * std::size_t(n_table_), 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, n_r), [&](const tbb::blocked_range<int>& rows) {
        for (int i = rows.begin(); i != rows.end(); ++i) {
            // Inverse of the mapping in the header (Bruneton 2017,
            // GetRMuFromTransmittanceTextureUv), in double precision.
            const double rho = H_ * double(i) / double(n_r - 1);
            const double r = std::min(std::sqrt(rho * rho + bottom_ * bottom_), top_);
            const double d_min = top_ - r, d_max = rho + H_;
            for (int j = 0; j < n_mu; ++j) {
                const double d = d_min + (d_max - d_min) * double(j) / double(n_mu - 1);
                const double mu =
                    d <= 0.0 ? 1.0 : clamp_cosine((H_ * H_ - rho * rho - d * d) / (2.0 * r * d));
                double* v =
                    &values_[(std::size_t(i) * std::size_t(n_mu) + std::size_t(j)) * std::size_t(n_table_)];
                for (int slot = 0; slot < n_table_; ++slot) {
                    const int k = table_slot_[slot];
                    const double c = density_integral(profiles_[std::size_t(k)], bottom_, r, mu, d);
                    v[slot] = log_offset_[k] > 0.0 ? std::log(c + log_offset_[k]) : c;
                }
            }
        }
    });
}

std::shared_ptr<const ColumnTable> ColumnTable::shared(const Atmosphere& atm) {
    // A handful of geometries: a session switches between a few presets.
    static std::mutex mutex;
    static std::vector<std::pair<Atmosphere, std::shared_ptr<const ColumnTable>>> cache;
    constexpr std::size_t kCapacity = 6;
    std::lock_guard lock(mutex);
    for (std::size_t i = 0; i < cache.size(); ++i)
        if (same_geometry(cache[i].first, atm)) {
            auto hit = cache[i];
            cache.erase(cache.begin() + std::ptrdiff_t(i));
            cache.push_back(hit);  // most recently used last
            return hit.second;
        }
    auto table = std::make_shared<const ColumnTable>(atm);
    if (cache.size() == kCapacity) cache.erase(cache.begin());
    cache.emplace_back(atm, table);
    return table;
}

template <int N>
void ColumnTable::interpolate(int i_r, const double* w_r, int i_mu, const double* w_mu, double* acc) const {
    for (int k = 0; k < N; ++k) acc[k] = 0.0;
    for (int a = 0; a < 4; ++a) {
        const double* row = &values_[(std::size_t(i_r + a) * std::size_t(n_mu_) + std::size_t(i_mu)) * N];
        double racc[N] = {};
        for (int b = 0; b < 4; ++b)
            for (int k = 0; k < N; ++k) racc[k] += w_mu[b] * row[N * b + k];
        for (int k = 0; k < N; ++k) acc[k] += w_r[a] * racc[k];
    }
}

void ColumnTable::lookup(double r, double mu, double out[3]) const {
    out[0] = out[1] = out[2] = 0.0;
    if (n_table_ == 0) return;
    r = std::clamp(r, bottom_, top_);
    const double rho = safe_sqrt((r - bottom_) * (r + bottom_));
    const double d = distance_to_top(r, mu, top_);
    const double d_min = top_ - r, d_max = rho + H_;
    const double x_mu = d_max > d_min ? (d - d_min) / (d_max - d_min) : 0.0;
    const Stencil sr = stencil(rho / H_, n_r_), sm = stencil(x_mu, n_mu_);
    double acc[3];
    switch (n_table_) {
        case 1:
            interpolate<1>(sr.first, sr.w.data(), sm.first, sm.w.data(), acc);
            break;
        case 2:
            interpolate<2>(sr.first, sr.w.data(), sm.first, sm.w.data(), acc);
            break;
        default:
            interpolate<3>(sr.first, sr.w.data(), sm.first, sm.w.data(), acc);
            break;
    }
    for (int slot = 0; slot < n_table_; ++slot) {
        const int k = table_slot_[slot];
        out[k] = std::max(0.0, log_offset_[k] > 0.0 ? std::exp(acc[slot]) - log_offset_[k] : acc[slot]);
    }
}

int ColumnTable::linear_pieces(int k, double r, double mu, double q, double length,
                               Ray::Piece* pieces) const {
    // Cut [0, length] at the lowest point and wherever the altitude crosses a breakpoint
    // (as optical_depth.cpp does), so that one linear formula holds on each piece.
    const DensityProfile& profile = profiles_[std::size_t(k)];
    std::array<double, kMaxPieces + 1> cuts;
    int n = 0;
    cuts[std::size_t(n++)] = 0.0;
    const double t_low = -r * mu;
    if (t_low > 0.0 && t_low < length) cuts[std::size_t(n++)] = t_low;
    for (double hb : breakpoints_[k]) {
        const double disc = sphere_discriminant(r, mu, bottom_ + hb);
        if (disc < 0.0) continue;
        const double sq = std::sqrt(disc);
        for (double t : {-r * mu - sq, -r * mu + sq})
            if (t > 0.0 && t < length) cuts[std::size_t(n++)] = t;
    }
    std::sort(cuts.begin(), cuts.begin() + n);
    const auto& layers = profile.layers();
    double cumulative = 0.0;
    int count = 0;
    for (int i = 0; i < n; ++i) {
        const double a_s = cuts[std::size_t(i)];
        const double b_s = i + 1 < n ? cuts[std::size_t(i + 1)] : length;
        // The formula in force on the piece: the layer holding its middle altitude, and
        // whether the clamp to [0, 1] is active there.
        const double h = radius_at(r, mu, 0.5 * (a_s + b_s)) - bottom_;
        const DensityLayer* layer = &layers.back();
        double bottom = 0.0;
        for (std::size_t j = 0; j + 1 < layers.size(); ++j) {
            bottom += layers[j].width_m;
            if (h < bottom) {
                layer = &layers[j];
                break;
            }
        }
        const double v = layer->linear_per_m * h + layer->constant;
        Ray::Piece p;
        p.start = a_s;
        p.cumulative = cumulative;
        p.a = v <= 0.0 ? 0.0 : v >= 1.0 ? 1.0 : layer->constant;
        p.b = (v <= 0.0 || v >= 1.0) ? 0.0 : layer->linear_per_m;
        p.g_start = distance_primitive(a_s + r * mu, q);
        const double g_end = distance_primitive(b_s + r * mu, q);
        // int (a + b (|x| - R)) ds = (a - b R) ds + b d(primitive)
        cumulative += (p.a - p.b * bottom_) * (b_s - a_s) + p.b * (g_end - p.g_start);
        pieces[count++] = p;
    }
    return count;
}

ColumnTable::Ray ColumnTable::ray(double r, double mu) const {
    Ray ray;
    ray.table_ = this;
    ray.r_ = std::clamp(r, bottom_, top_);
    ray.mu_ = clamp_cosine(mu);
    ray.q_ = ray.r_ * safe_sqrt((1.0 - ray.mu_) * (1.0 + ray.mu_));
    ray.hits_ground_ = ray_hits_ground(ray.r_, ray.mu_, bottom_);
    ray.length_ = distance_to_boundary(ray.r_, ray.mu_, bottom_, top_);
    if (n_table_ > 0) lookup(ray.r_, ray.hits_ground_ ? -ray.mu_ : ray.mu_, ray.base_);
    for (int k = 0; k < 3; ++k)
        if (kind_[k] == Kind::Linear)
            ray.n_pieces_[k] = linear_pieces(k, ray.r_, ray.mu_, ray.q_, ray.length_, ray.pieces_[k]);
    return ray;
}

ColumnDensity ColumnTable::Ray::upto(double s) const {
    s = std::clamp(s, 0.0, length_);
    double c[3] = {0.0, 0.0, 0.0};
    if (table_->n_table_ > 0 && s > 0.0) {
        const double r_s = radius_at(r_, mu_, s);
        const double mu_s = mu_at(r_, mu_, s, r_s);
        double here[3];
        table_->lookup(r_s, hits_ground_ ? -mu_s : mu_s, here);
        for (int k = 0; k < 3; ++k)
            c[k] = std::max(0.0, hits_ground_ ? here[k] - base_[k] : base_[k] - here[k]);
    }
    for (int k = 0; k < 3; ++k) {
        if (n_pieces_[k] == 0) continue;
        int i = n_pieces_[k] - 1;
        while (i > 0 && pieces_[k][i].start > s) --i;
        const Piece& p = pieces_[k][i];
        const double g = distance_primitive(s + r_ * mu_, q_);
        c[k] = std::max(0.0,
                        p.cumulative + (p.a - p.b * table_->bottom_) * (s - p.start) + p.b * (g - p.g_start));
    }
    return {c[0], c[1], c[2]};
}

ColumnDensity ColumnTable::to_top(double r, double mu) const {
    r = std::clamp(r, bottom_, top_);
    // Below the horizon: the horizon (the contract asks for rays that miss the ground).
    const double mu_horizon = -safe_sqrt((r - bottom_) * (r + bottom_)) / r;
    mu = std::max(clamp_cosine(mu), mu_horizon);
    double c[3];
    lookup(r, mu, c);
    bool any_linear = false;
    for (int k = 0; k < 3; ++k) any_linear = any_linear || kind_[k] == Kind::Linear;
    if (any_linear) {
        const double q = r * safe_sqrt((1.0 - mu) * (1.0 + mu));
        const double length = distance_to_top(r, mu, top_);
        Ray::Piece pieces[kMaxPieces];
        for (int k = 0; k < 3; ++k) {
            if (kind_[k] != Kind::Linear) continue;
            const int n = linear_pieces(k, r, mu, q, length, pieces);
            const Ray::Piece& p = pieces[n - 1];
            c[k] = std::max(0.0, p.cumulative + (p.a - p.b * bottom_) * (length - p.start) +
                                     p.b * (distance_primitive(length + r * mu, q) - p.g_start));
        }
    }
    return {c[0], c[1], c[2]};
}

}  // namespace welkin
