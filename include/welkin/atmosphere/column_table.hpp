// SPDX-License-Identifier: Apache-2.0
// Fast, exact-enough column densities for the reference path tracer's transmittances.
//
// Why. The path tracer needs the transmittance towards the sun at every scattering vertex
// and inverts the optical depth along every free flight: millions of optical depths per
// image. optical_depth.hpp's graded Gauss-Legendre is exact but costs ~10^3 density
// evaluations per ray. The column densities of the three constituents (Rayleigh, Mie,
// absorption) depend on the geometry only, not on the wavelength, so one evaluator of the
// three columns serves every channel (3 or 48): the optical depth of channel c is their
// dot product with the channel's coefficients (optical_depth()).
//
// Two kinds of constituent:
//
// 1. Piecewise-linear profiles (every layer has exp_term = 0: the ozone tent, a constant
//    or a zero layer) are integrated in closed form. Along the ray from radius r with
//    zenith cosine mu, with u = s + r mu and q = r sqrt(1 - mu^2), the distance to the
//    centre is sqrt(u^2 + q^2) and
//        int sqrt(u^2 + q^2) du = (u sqrt(u^2 + q^2) + q^2 asinh(u / q)) / 2,
//    so a layer rho = a + b h integrates to (a - b R) ds + b d(that primitive). The ray
//    is cut where it crosses the profile's breakpoints (as in optical_depth.cpp) and at
//    its lowest point, so each piece is one linear (or clamped, constant) formula. This
//    is exact where a table would not be: the tent's kinks give columns that behave like
//    (h_b - h_tangent)^{3/2} for rays grazing a breakpoint, which no interpolation
//    resolves.
//
// 2. Any other profile (the exponentials) is tabulated: columns from (r, mu) to the top
//    of the atmosphere on Bruneton 2017's transmittance-texture parametrisation
//    (functions.glsl, GetTransmittanceTextureUvFromRMu; here in double precision and
//    without texel-centre offsets): with H = sqrt(top^2 - R^2), rho = sqrt(r^2 - R^2),
//    d the distance to the top, d_min = top - r and d_max = rho + H,
//        x_r = rho / H,    x_mu = (d - d_min) / (d_max - d_min),
//    which maps exactly the rays that do not hit the ground onto [0, 1]^2 and spends the
//    nodes where the columns change fastest. Nodes hold density_integral's exact columns;
//    lookups interpolate with 4-point Lagrange (cubic) polynomials in both coordinates.
//    A single decaying exponential of scale height H_s is stored as log(C + c0) with
//    c0 = max(1 mm, 30 H_s rho(top)): the logarithm is nearly linear in the lowest
//    altitude of the ray, so a 1.2 km aerosol layer keeps its relative accuracy on rays
//    that graze it from far above, while the offset keeps the storage linear near the top
//    of the atmosphere, where the columns vanish like a square root. Other profiles are
//    stored as C.
//    Along a ray that does not hit the ground the column over [0, s] is
//    C(r, mu) - C(r_s, mu_s); along one that hits it both are taken on the reversed ray,
//    C(r_s, -mu_s) - C(r, -mu), which never does (Bruneton 2017, GetTransmittance). The
//    difference keeps the absolute error of the optical depth, which is what a
//    transmittance needs.
//
// Accuracy (tests/cpp/test_optical_depth.cpp, against density_integral on random rays of
// every preset at 48 wavelengths): optical depths to the top within 1e-5 relative plus
// 1e-7 absolute (worst measured: 0.6 of that bound); along segments, where the difference
// of two lookups loses the relative digits, within 1e-5 absolute, i.e. transmittances to
// 1e-5 relative (worst measured: 4e-6, the "polluted" aerosol at 360 nm).
//
// Thread safety: a built table is immutable. shared() hands out one cached table per
// geometry (radii and density profiles), building it once, in parallel, under a lock.
#pragma once

#include <memory>
#include <vector>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/atmosphere/optical_depth.hpp"

namespace welkin {

class ColumnTable {
public:
    // Builds the table (n_r x n_mu nodes, each in [8, 16384]) for `atm`'s radii and
    // density profiles.
    explicit ColumnTable(const Atmosphere& atm, int n_r = kDefaultRadiusNodes,
                         int n_mu = kDefaultCosineNodes);

    // One table per distinct geometry, built on first use and kept for the process (a
    // cache of the few most recently used geometries).
    static std::shared_ptr<const ColumnTable> shared(const Atmosphere& atm);

    // Profiles with more breakpoints than this are tabulated instead of integrated in
    // closed form.
    static constexpr int kMaxBreakpoints = 12;
    static constexpr int kMaxPieces = 2 * kMaxBreakpoints + 2;

    // Columns (m) of a straight ray inside the atmosphere, from its start.
    class Ray {
    public:
        // Columns over [0, s] (s is clamped to [0, length()]); never negative.
        ColumnDensity upto(double s) const;
        // Distance from the start to where the ray leaves the atmosphere (the ground if
        // it hits it, else the top).
        double length() const { return length_; }
        bool hits_ground() const { return hits_ground_; }

    private:
        friend class ColumnTable;
        // [start, next piece's start) of one formula of a piecewise-linear profile:
        // rho = a + b h there; `cumulative` is the column over [0, start] and g_start the
        // primitive at start.
        struct Piece {
            double start, cumulative, a, b, g_start;
        };
        const ColumnTable* table_ = nullptr;
        double r_ = 0, mu_ = 0, q_ = 0, length_ = 0;
        bool hits_ground_ = false;
        double base_[3] = {0, 0, 0};  // tabulated constituents: column at the start
        int n_pieces_[3] = {0, 0, 0};
        Piece pieces_[3][kMaxPieces];  // analytic constituents
    };

    // The ray from radius r (clamped to [R, top]) with zenith cosine mu.
    Ray ray(double r, double mu) const;

    // Columns (m) from (r, mu) to the top of the atmosphere; mu must not hit the ground
    // (below the horizon it is treated as the horizon).
    ColumnDensity to_top(double r, double mu) const;

    static constexpr int kDefaultRadiusNodes = 192;
    static constexpr int kDefaultCosineNodes = 384;

    double bottom_radius_m() const { return bottom_; }
    double top_radius_m() const { return top_; }

private:
    enum class Kind { Zero, Linear, Table };
    // Tabulated part of to_top (analytic constituents left 0).
    void lookup(double r, double mu, double out[3]) const;
    template <int N>
    void interpolate(int i_r, const double* w_r, int i_mu, const double* w_mu, double* acc) const;
    // Pieces of analytic constituent k along [0, length] of the ray; returns their count.
    int linear_pieces(int k, double r, double mu, double q, double length, Ray::Piece* pieces) const;

    double bottom_, top_, H_;
    int n_r_, n_mu_;
    Kind kind_[3];
    double log_offset_[3];  // c0 of the logarithmic storage; 0 = stored linearly
    std::vector<DensityProfile> profiles_;
    std::vector<double> breakpoints_[3];  // of each profile (DensityProfile::breakpoints_m)
    // Node values of the tabulated constituents, [i_r][i_mu][slot], slot s holding
    // constituent table_slot_[s].
    int n_table_ = 0;
    int table_slot_[3] = {0, 0, 0};
    std::vector<double> values_;
};

}  // namespace welkin
