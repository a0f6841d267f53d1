// SPDX-License-Identifier: Apache-2.0
// The reference sky (Monte-Carlo path tracing): against the peer table
// (tests/data/bruneton2017_sky_subset.csv, Bruneton 2017's reference model),
// against closed forms and an independent deterministic quadrature, energy conservation,
// its standard error, determinism, and its behaviour at the edges of its domain.
//
// Runtime: about 21 s on one free core in a Release build (2.4 us of CPU per path with 3
// wavelengths; the peer comparison dominates); the paths per direction used are printed
// by each Monte-Carlo test.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "peer_table.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <oneapi/tbb/global_control.h>

#include "welkin/atmosphere/column_table.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/phase.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/quadrature.hpp"
#include "welkin/sky/reference.hpp"

using namespace welkin;

namespace {

glm::dvec3 view_direction(double zenith_deg, double azimuth_deg) {
    const double z = zenith_deg * kDegree, a = azimuth_deg * kDegree;
    return {std::sin(z) * std::cos(a), std::sin(z) * std::sin(a), std::cos(z)};
}

Observer sun_at(double zenith_deg, double altitude_m = 0.0) {
    Observer o;
    o.altitude_m = altitude_m;
    o.sun_direction = view_direction(zenith_deg, 0.0);
    return o;
}

struct SkyRun {
    std::vector<float> radiance, standard_error;
};

SkyRun run(const ReferenceSky& sky, const Atmosphere& atm, const Observer& obs,
           const std::vector<glm::dvec3>& dirs) {
    SkyRun r;
    r.radiance.resize(dirs.size() * atm.channels());
    r.standard_error.resize(dirs.size() * atm.channels());
    sky.radiance(atm, obs, dirs, r.radiance, r.standard_error);
    return r;
}

SkyOptions paths(int n, std::uint64_t seed = 1) {
    SkyOptions o;
    o.reference_paths = n;
    o.seed = seed;
    return o;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}
double median_abs(std::vector<double> v) {
    for (double& x : v) x = std::abs(x);
    return median(v);
}
double worst(const std::vector<double>& v) {
    double w = 0.0;
    for (double x : v) w = std::max(w, std::abs(x));
    return w;
}

// ---------------------------------------------------------------------------------------
// The peer table, with each row's geometry in degrees.
struct PeerRow {
    double sun_zenith, view_zenith, azimuth;
    std::map<std::string, double> v;
};

std::vector<PeerRow> load_peer() {
    std::vector<PeerRow> rows;
    for (const test::PeerRow& r : test::read_peer_table())
        rows.push_back({r["sun_zenith_deg"], r["view_zenith_deg"], r["rel_azimuth_deg"], r.v});
    return rows;
}

const char* const kBands[3] = {"680nm", "550nm", "440nm"};

// Bruneton 2017's single scattering quadrature (functions.glsl, ComputeSingleScattering):
// the trapezoid rule with n intervals from the camera to the nearest atmosphere boundary,
// integrand T(camera, y) T_sun(y) rho(y), times the scattering coefficients, the solar
// irradiance and the phase functions. Transmittances from our column table, so with n = 50
// this reproduces the peer's L1d column, and with n -> infinity the exact single scattering.
std::vector<double> trapezoid_single_scattering(const Atmosphere& atm, const ColumnTable& table,
                                                double altitude_m, const glm::dvec3& v, const glm::dvec3& s,
                                                int n) {
    const double R = atm.bottom_radius_m, r = R + altitude_m, mu = v.z, mu_s = s.z;
    const double nu = glm::dot(v, s);
    const ColumnTable::Ray ray = table.ray(r, mu);
    const double dx = ray.length() / n;
    std::vector<double> rayleigh(atm.channels(), 0.0), mie(atm.channels(), 0.0);
    for (int i = 0; i <= n; ++i) {
        const double d = i * dx, r_d = radius_at(r, mu, d);
        const double mu_s_d = clamp_cosine((r * mu_s + d * nu) / r_d);
        if (ray_hits_ground(r_d, mu_s_d, R)) continue;
        const ColumnDensity view = ray.upto(d), sun = table.to_top(r_d, mu_s_d);
        const double w = (i == 0 || i == n) ? 0.5 : 1.0;
        for (std::size_t c = 0; c < atm.channels(); ++c) {
            const double t = std::exp(-optical_depth(atm, c, view) - optical_depth(atm, c, sun));
            rayleigh[c] += w * t * atm.rayleigh_density.density(r_d - R);
            mie[c] += w * t * atm.mie_density.density(r_d - R);
        }
    }
    std::vector<double> out(atm.channels());
    for (std::size_t c = 0; c < atm.channels(); ++c)
        out[c] = dx * atm.solar_irradiance[c] *
                 (rayleigh[c] * atm.rayleigh_scattering[c] * rayleigh_phase(nu) +
                  mie[c] * atm.mie_scattering[c] * mie_phase(atm.mie_phase, nu, atm.mie_g));
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Single scattering, no Monte Carlo. (1) Our transmittances, geometry, phase functions and
// solar irradiance reproduce the peer's directly integrated single scattering (L1d) when
// we use its own 50-step trapezoid rule: this ties every input of the method to an
// implementation nobody here wrote. (2) The method's single scattering (its quadrature,
// max_scattering_order = 1) equals the limit of that trapezoid rule (Richardson
// extrapolation of 2000 and 4000 steps). (3) Printed, not asserted: the peer's 50-step
// rule itself is off by up to ~6 % (Mie, 1.2 km scale height, sampled every ~1.2 km on
// steep rays), which is why the all-orders comparison below removes it.
TEST(ReferenceSkyPeer, SingleScatteringReproducesPeerQuadratureAndItsLimit) {
    const std::vector<PeerRow> rows = load_peer();
    ASSERT_EQ(rows.size(), 135u);
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const ColumnTable table(atm);
    const ReferenceSky single(paths(1), 1);
    std::vector<double> replica_err[3], limit_err[3], peer_quadrature_err[3];
    for (const PeerRow& row : rows) {
        if (!(row.view_zenith < 90.0)) continue;
        const Observer obs = sun_at(row.sun_zenith);
        const glm::dvec3 v = view_direction(row.view_zenith, row.azimuth);
        const std::vector<double> replica =
            trapezoid_single_scattering(atm, table, 0.0, v, obs.sun_direction, 50);
        const std::vector<double> t1 =
            trapezoid_single_scattering(atm, table, 0.0, v, obs.sun_direction, 2000);
        const std::vector<double> t2 =
            trapezoid_single_scattering(atm, table, 0.0, v, obs.sun_direction, 4000);
        const SkyRun ours = run(single, atm, obs, {v});
        for (int c = 0; c < 3; ++c) {
            const double peer = row.v.at(std::string("L1d_") + kBands[c]);
            const double limit = (4.0 * t2[std::size_t(c)] - t1[std::size_t(c)]) / 3.0;
            replica_err[c].push_back(replica[std::size_t(c)] / peer - 1.0);
            limit_err[c].push_back(ours.radiance[std::size_t(c)] / limit - 1.0);
            peer_quadrature_err[c].push_back(peer / ours.radiance[std::size_t(c)] - 1.0);
            EXPECT_EQ(ours.standard_error[std::size_t(c)], 0.0f);
        }
    }
    for (int c = 0; c < 3; ++c) {
        std::printf(
            "[ single scattering %s ] 50-step replica vs peer L1d: median %.5f worst %.5f; "
            "method vs trapezoid limit: worst %.1e; peer L1d vs method: median %.4f "
            "worst %.4f (the peer's quadrature)\n",
            kBands[c], median_abs(replica_err[c]), worst(replica_err[c]), worst(limit_err[c]),
            median_abs(peer_quadrature_err[c]), worst(peer_quadrature_err[c]));
        EXPECT_LT(worst(replica_err[c]), 0.005) << kBands[c];
        EXPECT_LT(worst(limit_err[c]), 1e-6) << kBands[c];
    }
}

// ---------------------------------------------------------------------------------------
// All orders against the peer. For each of the peer's sun zeniths (0, 30, 60 deg), the
// distinct view directions above the horizon (the zenith appears once: 26 per sun).
struct PeerGeometry {
    double sun_zenith;
    std::vector<glm::dvec3> dirs;
    // Index of the direction of a peer row.
    std::size_t index_of(const PeerRow& row) const {
        const glm::dvec3 v = view_direction(row.view_zenith, row.view_zenith == 0.0 ? 0.0 : row.azimuth);
        for (std::size_t i = 0; i < dirs.size(); ++i)
            if (glm::length(dirs[i] - v) < 1e-12) return i;
        ADD_FAILURE() << "no direction for row";
        return 0;
    }
};

std::vector<PeerGeometry> peer_geometries(const std::vector<PeerRow>& rows) {
    std::vector<PeerGeometry> out;
    for (double sz : {0.0, 30.0, 60.0}) {
        PeerGeometry geo{sz, {}};
        for (const PeerRow& row : rows) {
            if (row.sun_zenith != sz || !(row.view_zenith < 90.0)) continue;
            if (row.view_zenith == 0.0 && row.azimuth != 0.0) continue;
            geo.dirs.push_back(view_direction(row.view_zenith, row.azimuth));
        }
        out.push_back(std::move(geo));
    }
    return out;
}

// The reference (all orders) and its 4-order truncation against the peer's L (4 orders),
// every row above the horizon. What is asserted, and why:
//  * The 4-order truncation, with the peer's single-scattering quadrature error removed
//    (its 50-step trapezoid minus the exact integral, both computed here with our
//    transmittances, the former checked against the peer's L1d above), must lie within
//    2 % of the peer for every row with the sun at the zenith.
//  * With the sun at 30 and 60 deg the peer's multiple scattering depends on the view
//    azimuth far more than ours (up to +-25 % of the multiple-scattering part at 440 nm,
//    i.e. up to 7.5 % of the total): there the rows are printed, and the azimuthal
//    structure of our second order is checked against an independent deterministic
//    quadrature instead (SecondOrderMatchesPlaneParallelQuadrature). The peer's structure is its
//    texture lookup; test_peer_multiple_scattering.cpp emulates it and asserts 2-2.5 % there.
//  * All orders vs the peer's 4 orders is printed: the 5th and higher orders add up to
//    ~2 % at 440 nm.
TEST(ReferenceSkyPeer, AllOrdersAgainstThePeer) {
    constexpr int kPaths = 32768;
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const ColumnTable table(atm);
    const ReferenceSky single(paths(1), 1);
    const std::vector<PeerRow> rows = load_peer();
    const std::vector<PeerGeometry> geos = peer_geometries(rows);
    std::vector<SkyRun> all, four;
    std::size_t directions = 0;
    const auto start = std::chrono::steady_clock::now();
    for (const PeerGeometry& geo : geos) {
        all.push_back(run(ReferenceSky(paths(kPaths, 11)), atm, sun_at(geo.sun_zenith), geo.dirs));
        directions += geo.dirs.size();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (const PeerGeometry& geo : geos)
        four.push_back(run(ReferenceSky(paths(kPaths, 13), 4), atm, sun_at(geo.sun_zenith), geo.dirs));
    std::map<double, std::vector<double>> raw_err[3], four_err[3];
    std::vector<double> rel_se[3];
    for (const PeerRow& row : rows) {
        if (!(row.view_zenith < 90.0)) continue;
        std::size_t g = 0;
        while (geos[g].sun_zenith != row.sun_zenith) ++g;
        const std::size_t i = geos[g].index_of(row);
        const Observer obs = sun_at(row.sun_zenith);
        const glm::dvec3 v = geos[g].dirs[i];
        const std::vector<double> peer_quadrature =
            trapezoid_single_scattering(atm, table, 0.0, v, obs.sun_direction, 50);
        const SkyRun exact_single = run(single, atm, obs, {v});
        std::printf("[ peer row sun %2.0f view %2.0f az %3.0f ]", row.sun_zenith, row.view_zenith,
                    row.azimuth);
        for (std::size_t c = 0; c < 3; ++c) {
            const double peer = row.v.at(std::string("L_") + kBands[c]);
            const double reference = all[g].radiance[i * 3 + c];
            const double truncated =
                four[g].radiance[i * 3 + c] - exact_single.radiance[c] + peer_quadrature[c];
            raw_err[c][row.sun_zenith].push_back(reference / peer - 1.0);
            four_err[c][row.sun_zenith].push_back(truncated / peer - 1.0);
            rel_se[c].push_back(all[g].standard_error[i * 3 + c] / reference);
            std::printf("  %s all %+.4f, 4 orders %+.4f", kBands[c], reference / peer - 1.0,
                        truncated / peer - 1.0);
            if (row.sun_zenith == 0.0) {
                EXPECT_LT(std::abs(truncated / peer - 1.0), 0.02)
                    << kBands[c] << " sun 0 view " << row.view_zenith << " az " << row.azimuth;
            }
        }
        std::printf("\n");
    }
    for (std::size_t c = 0; c < 3; ++c) {
        for (double sz : {0.0, 30.0, 60.0})
            std::printf(
                "[ peer %s sun %2.0f ] all orders vs peer: median |err| %.4f worst %.4f;  "
                "4 orders, peer quadrature removed: median |err| %.4f worst %.4f\n",
                kBands[c], sz, median_abs(raw_err[c][sz]), worst(raw_err[c][sz]), median_abs(four_err[c][sz]),
                worst(four_err[c][sz]));
        // The standard error is small: under 0.5 % of every value.
        std::printf("[ peer %s ] relative standard error: median %.5f worst %.5f\n", kBands[c],
                    median(rel_se[c]), worst(rel_se[c]));
        EXPECT_LT(worst(rel_se[c]), 0.005) << kBands[c];
    }
    std::printf(
        "[ peer ] %d paths per direction; all orders: %zu directions in %.1f s, %.0f ms "
        "per direction\n",
        kPaths, directions, seconds, 1e3 * seconds / double(directions));
}

// The standard error is honest: two seeds differ by amounts whose normalised spread
// z = (a - b) / sqrt(se_a^2 + se_b^2) has an RMS of 1, over the peer's 78 directions and 3
// wavelengths.
TEST(ReferenceSkyPeer, StandardErrorMatchesTheSpreadBetweenSeeds) {
    constexpr int kPaths = 4096;
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    std::vector<double> z;
    for (const PeerGeometry& geo : peer_geometries(load_peer())) {
        const SkyRun a = run(ReferenceSky(paths(kPaths, 21)), atm, sun_at(geo.sun_zenith), geo.dirs);
        const SkyRun b = run(ReferenceSky(paths(kPaths, 22)), atm, sun_at(geo.sun_zenith), geo.dirs);
        for (std::size_t k = 0; k < a.radiance.size(); ++k) {
            ASSERT_GT(a.standard_error[k], 0.0f);
            ASSERT_GT(b.standard_error[k], 0.0f);
            z.push_back((a.radiance[k] - b.radiance[k]) /
                        std::hypot(a.standard_error[k], b.standard_error[k]));
        }
    }
    double rms = 0.0;
    for (double x : z) rms += x * x / double(z.size());
    rms = std::sqrt(rms);
    std::printf(
        "[ standard error ] %zu values, two seeds of %d paths: RMS of z = %.3f, worst "
        "|z| = %.2f\n",
        z.size(), kPaths, rms, worst(z));
    // The 234 values are correlated across the channels of a direction (~80 independent
    // directions), so the RMS scatters by about +-0.1 between seed pairs (0.92 to 1.14
    // over 8 pairs while writing this); the bounds are ~3 times that.
    EXPECT_GT(rms, 0.75);
    EXPECT_LT(rms, 1.3);
    EXPECT_LT(worst(z), 5.0);
}

// ---------------------------------------------------------------------------------------
// Second order, independently: a deterministic quadrature of the light scattered exactly
// twice in the air, in a plane-parallel atmosphere over a black ground, against the
// method with max_scattering_order 2 on a planet of radius 1e9 m (flat to 1e-5 over the
// paths that matter). The quadrature shares nothing with the method but the phase
// functions and the density profiles:
//
//   L2 = int_0^Z dz / mu_v e^{-(tau(0) - tau(z)) / mu_v} sum_j sigma_j(z)
//          int dw p_j(w . v) sum_k p_k(w . s) G_k(z, mu_w),
//   G_k(z, mu) = int along w of e^{-|tau(z) - tau(z')| / |mu|} sigma_k(z') e^{-tau(z') / mu_s} dz' / |mu|,
//
// tau the vertical optical depth to the top (closed form for exponential layers). G is
// accumulated level by level, exactly for an integrand linear in optical depth within a
// level (so grazing mu costs nothing in accuracy); 2001 levels, directions: 48
// Gauss-Legendre cosines per hemisphere times 360 azimuths; doubling all three changes
// the result by < 1e-5. This checks the azimuthal structure of the multiple
// scattering, which the peer's table does not settle at sun zeniths 30 and 60 deg.
namespace {

std::vector<double> plane_parallel_second_order(const Atmosphere& atm, const glm::dvec3& v,
                                                const glm::dvec3& s) {
    const double Z = atm.top_radius_m - atm.bottom_radius_m;
    const double HR = *atm.rayleigh_density.exponential_scale_height_m();
    const double HM = *atm.mie_density.exponential_scale_height_m();
    const int N = 2001;
    std::vector<double> z(N);
    for (int i = 0; i < N; ++i)  // graded: 0.08 m at the ground, 240 m at the top
        z[std::size_t(i)] = Z * std::expm1(8.0 * i / (N - 1.0)) / std::expm1(8.0);
    // Gauss-Legendre cosines on (0, 1).
    const int M = 48;
    std::vector<double> mu_up, w_up;
    gauss_legendre_unit(M, mu_up, w_up);
    std::vector<double> mus, wmu;  // downward then upward
    for (int i = 0; i < M; ++i) mus.push_back(-mu_up[std::size_t(i)]), wmu.push_back(w_up[std::size_t(i)]);
    for (int i = 0; i < M; ++i) mus.push_back(mu_up[std::size_t(i)]), wmu.push_back(w_up[std::size_t(i)]);
    // Angular kernels A_jk(mu) = w_mu int dphi p_j(w . v) p_k(w . s), j, k in {R, M}.
    const int P = 360;
    std::vector<std::array<double, 4>> A(mus.size(), {0, 0, 0, 0});
    for (std::size_t m = 0; m < mus.size(); ++m)
        for (int p = 0; p < P; ++p) {
            const double phi = (p + 0.5) * kTwoPi / P, st = std::sqrt(1.0 - mus[m] * mus[m]);
            const glm::dvec3 w(st * std::cos(phi), st * std::sin(phi), mus[m]);
            const double nv = glm::dot(w, v), ns = glm::dot(w, s);
            const double pv[2] = {rayleigh_phase(nv), mie_phase(atm.mie_phase, nv, atm.mie_g)};
            const double ps[2] = {rayleigh_phase(ns), mie_phase(atm.mie_phase, ns, atm.mie_g)};
            for (int j = 0; j < 2; ++j)
                for (int k = 0; k < 2; ++k)
                    A[m][std::size_t(2 * j + k)] += wmu[m] * kTwoPi / P * pv[j] * ps[k];
        }
    std::vector<double> out(atm.channels());
    std::vector<double> tau(N), sig_t(N), src[2];
    src[0].resize(N);
    src[1].resize(N);
    for (std::size_t c = 0; c < atm.channels(); ++c) {
        const double bR = atm.rayleigh_scattering[c], bMs = atm.mie_scattering[c],
                     bMe = atm.mie_extinction[c];
        for (int i = 0; i < N; ++i) {
            const double zi = z[std::size_t(i)];
            tau[std::size_t(i)] = bR * HR * (std::exp(-zi / HR) - std::exp(-Z / HR)) +
                                  bMe * HM * (std::exp(-zi / HM) - std::exp(-Z / HM));
            sig_t[std::size_t(i)] = bR * std::exp(-zi / HR) + bMe * std::exp(-zi / HM);
            const double tsun = std::exp(-tau[std::size_t(i)] / s.z);
            // Source over extinction, the f integrated linearly in optical depth.
            src[0][std::size_t(i)] = bR * std::exp(-zi / HR) * tsun / sig_t[std::size_t(i)];
            src[1][std::size_t(i)] = bMs * std::exp(-zi / HM) * tsun / sig_t[std::size_t(i)];
        }
        // int_0^D e^{-u/mu} (f0 + (f1 - f0) u / D) du / mu, x = D / mu.
        auto level = [](double f0, double f1, double x) {
            const double e = std::exp(-x), a = -std::expm1(-x);
            return f0 * a + (f1 - f0) * (x > 1e-8 ? a / x - e : 0.5 * x);
        };
        // G[k][i][m]
        std::vector<double> G[2];
        for (int k = 0; k < 2; ++k) {
            G[k].assign(std::size_t(N) * mus.size(), 0.0);
            for (std::size_t m = 0; m < mus.size(); ++m) {
                const double am = std::abs(mus[m]);
                if (mus[m] > 0.0) {  // light from above: accumulate from the top down
                    for (int i = N - 2; i >= 0; --i) {
                        const double x = (tau[std::size_t(i)] - tau[std::size_t(i + 1)]) / am;
                        G[k][std::size_t(i) * mus.size() + m] =
                            std::exp(-x) * G[k][std::size_t(i + 1) * mus.size() + m] +
                            level(src[k][std::size_t(i)], src[k][std::size_t(i + 1)], x);
                    }
                } else {  // light from below (black ground): from the ground up
                    for (int i = 1; i < N; ++i) {
                        const double x = (tau[std::size_t(i - 1)] - tau[std::size_t(i)]) / am;
                        G[k][std::size_t(i) * mus.size() + m] =
                            std::exp(-x) * G[k][std::size_t(i - 1) * mus.size() + m] +
                            level(src[k][std::size_t(i)], src[k][std::size_t(i - 1)], x);
                    }
                }
            }
        }
        double sum = 0.0;
        for (int i = 0; i < N; ++i) {
            const double zi = z[std::size_t(i)];
            const double sj[2] = {bR * std::exp(-zi / HR), bMs * std::exp(-zi / HM)};
            double inner = 0.0;
            for (std::size_t m = 0; m < mus.size(); ++m)
                for (int j = 0; j < 2; ++j)
                    for (int k = 0; k < 2; ++k)
                        inner += sj[j] * A[m][std::size_t(2 * j + k)] * G[k][std::size_t(i) * mus.size() + m];
            const double wz = 0.5 * ((i > 0 ? zi - z[std::size_t(i - 1)] : 0.0) +
                                     (i + 1 < N ? z[std::size_t(i + 1)] - zi : 0.0));
            sum += wz * std::exp(-(tau[0] - tau[std::size_t(i)]) / v.z) / v.z * inner;
        }
        out[c] = sum * atm.solar_irradiance[c];
    }
    return out;
}

}  // namespace

TEST(ReferenceSkyIndependent, SecondOrderMatchesPlaneParallelQuadrature) {
    Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    atm.bottom_radius_m = 1e9;
    atm.top_radius_m = 1e9 + 60e3;
    atm.absorption_density = DensityProfile::zero();
    for (std::size_t c = 0; c < atm.channels(); ++c) {
        atm.ground_albedo[c] = 0.0;
        atm.solar_irradiance[c] = 1.0;
    }
    const int n = 32768;
    const Observer obs = sun_at(30.0);
    const std::vector<glm::dvec3> dirs = {view_direction(30, 0), view_direction(30, 90),
                                          view_direction(30, 180), view_direction(75, 0),
                                          view_direction(75, 180)};
    const SkyRun two = run(ReferenceSky(paths(n, 5), 2), atm, obs, dirs);
    const SkyRun one = run(ReferenceSky(paths(1), 1), atm, obs, dirs);
    for (std::size_t i = 0; i < dirs.size(); ++i) {
        const std::vector<double> q = plane_parallel_second_order(atm, dirs[i], obs.sun_direction);
        std::printf("[ second order, sun 30, view %.0f az %.0f ]", std::acos(dirs[i].z) / kDegree,
                    std::atan2(dirs[i].y, dirs[i].x) / kDegree);
        for (std::size_t c = 0; c < 3; ++c) {
            const double mc = two.radiance[i * 3 + c] - one.radiance[i * 3 + c];
            const double se = two.standard_error[i * 3 + c];
            std::printf("  %s %.5e vs %.5e (%+.4f, se %.4f)", kBands[c], mc, q[c], mc / q[c] - 1.0,
                        se / q[c]);
            // 4 standard errors, plus 0.5 % for the curvature of the 1e9 m planet on grazing
            // paths (the quadrature itself is converged to 1e-5).
            EXPECT_NEAR(mc / q[c], 1.0, 0.005 + 4.0 * se / q[c]) << kBands[c] << " direction " << i;
        }
        std::printf("\n");
    }
    std::printf("[ second order ] %d paths per direction\n", n);
}

// ---------------------------------------------------------------------------------------
// Closed forms in a homogeneous layer on a planet of radius 1e9 m (plane-parallel to
// ~1e-5 over the paths used), sun at the zenith.
namespace {

// A homogeneous layer of thickness Z: constant densities, Rayleigh, HG Mie and absorption.
Atmosphere homogeneous_layer(double Z, std::vector<double> rayleigh, double mie_scattering,
                             double mie_extinction, double absorption, double albedo) {
    Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    atm.name = "homogeneous";
    atm.bottom_radius_m = 1e9;
    atm.top_radius_m = 1e9 + Z;
    const DensityProfile one({DensityLayer{0.0, 0.0, 0.0, 0.0, 1.0}});
    atm.rayleigh_density = one;
    atm.mie_density = one;
    atm.absorption_density = one;
    atm.mie_phase = MiePhaseModel::HenyeyGreenstein;
    atm.mie_g = 0.6;
    for (std::size_t c = 0; c < atm.channels(); ++c) {
        atm.solar_irradiance[c] = 1.0;
        atm.rayleigh_scattering[c] = rayleigh[c];
        atm.mie_scattering[c] = mie_scattering;
        atm.mie_extinction[c] = mie_extinction;
        atm.absorption_extinction[c] = absorption;
        atm.ground_albedo[c] = albedo;
    }
    atm.validate();
    return atm;
}

}  // namespace

// Single scattering, sun at the zenith, view at zenith cosine mu (nu = mu): the point at
// distance t is seen through e^{-s t} and lit through e^{-s (Z - t mu)}, so
//   L1 = E (sigma_R p_R(mu) + sigma_M p_HG(mu)) e^{-s Z} (1 - e^{-s Z (1 - mu) / mu}) / (s (1 - mu))
// (Z / mu... -> Z at mu = 1), s the extinction.
TEST(ReferenceSkyClosedForm, SingleScatteringInAHomogeneousLayer) {
    const double Z = 10e3;
    const Atmosphere atm = homogeneous_layer(Z, {1e-5, 3e-5, 8e-5}, 1e-5, 1.5e-5, 2e-6, 0.3);
    const ReferenceSky single(paths(1), 1);
    for (double vz : {0.0, 30.0, 60.0}) {
        const SkyRun r = run(single, atm, sun_at(0.0), {view_direction(vz, 0.0)});
        const double mu = std::cos(vz * kDegree);
        for (std::size_t c = 0; c < 3; ++c) {
            const double s = atm.rayleigh_scattering[c] + 1.5e-5 + 2e-6;
            const double path = mu == 1.0 ? Z : -std::expm1(-s * Z * (1.0 - mu) / mu) / (s * (1.0 - mu));
            const double exact =
                (atm.rayleigh_scattering[c] * rayleigh_phase(mu) + 1e-5 * henyey_greenstein_phase(mu, 0.6)) *
                std::exp(-s * Z) * path;
            EXPECT_NEAR(r.radiance[c] / exact, 1.0, 3e-5) << "view " << vz << " channel " << c;
            EXPECT_EQ(r.standard_error[c], 0.0f);
        }
    }
}

// Ground reflection, second order: sunlight reaching the Lambertian ground (albedo rho)
// and scattered once by Rayleigh air towards a camera on the ground looking up at zenith
// cosine mu_v. Ground radiance rho/pi E e^{-tau}; the air at distance t sees it from
// downward cosines mu through e^{-s t mu_v / mu}; the azimuthal mean of
// 1 + (w . v)^2 is 1 + mu^2 mu_v^2 + (1 - mu^2)(1 - mu_v^2) / 2. So
//   dL = E e^{-tau} rho/pi 3/8 int_0^1 [1 + mu^2 mu_v^2 + (1 - mu^2)(1 - mu_v^2)/2]
//        (1 - e^{-tau (1/mu_v + 1/mu)}) / (1 + mu_v / mu) dmu,
// the difference between orders <= 2 with albedo 1 and albedo 0 (same seed: the paths
// are the same up to the ground, so the difference is exactly the ground's share).
TEST(ReferenceSkyClosedForm, GroundReflectedLightScatteredOnce) {
    const double Z = 10e3;
    const std::vector<double> sigma = {1e-5, 3e-5, 6e-5};
    const Atmosphere white = homogeneous_layer(Z, sigma, 0.0, 0.0, 0.0, 1.0);
    const Atmosphere black = homogeneous_layer(Z, sigma, 0.0, 0.0, 0.0, 0.0);
    const int n = 16384;
    const ReferenceSky sky(paths(n, 3), 2);
    std::vector<double> x, w;
    gauss_legendre_unit(64, x, w);
    for (double vz : {0.0, 50.0}) {
        const std::vector<glm::dvec3> dirs = {view_direction(vz, 0.0)};
        const SkyRun a = run(sky, white, sun_at(0.0), dirs), b = run(sky, black, sun_at(0.0), dirs);
        const double mv = std::cos(vz * kDegree);
        for (std::size_t c = 0; c < 3; ++c) {
            const double tau = sigma[c] * Z;
            double integral = 0.0;
            for (std::size_t i = 0; i < x.size(); ++i) {
                const double mu = x[i];
                integral += w[i] * (1.0 + mu * mu * mv * mv + 0.5 * (1.0 - mu * mu) * (1.0 - mv * mv)) *
                            -std::expm1(-tau * (1.0 / mv + 1.0 / mu)) / (1.0 + mv / mu);
            }
            const double exact = std::exp(-tau) / kPi * 3.0 / 8.0 * integral;
            const double mc = a.radiance[c] - b.radiance[c];
            std::printf("[ ground, view %2.0f, tau %.2f ] %.6e vs %.6e (%+.5f, se %.5f)\n", vz, tau, mc,
                        exact, mc / exact - 1.0, a.standard_error[c] / exact);
            EXPECT_NEAR(mc / exact, 1.0, 4.0 * a.standard_error[c] / exact + 1e-4);
        }
    }
    std::printf("[ ground ] %d paths per direction\n", n);
}

// Energy conservation, all orders: a conservative layer (no absorption) over a black
// ground reflects or transmits everything it receives, so with the sun at the zenith
//   F_up(top) + F_down,diffuse(ground) = E (1 - e^{-tau}),
// F = 2 pi int_0^1 L(mu) mu dmu: the sky seen from the ground looking up plus the path
// radiance seen from just above the top looking down (which is everything that leaves:
// the ground is black). 24 Gauss-Legendre cosines per hemisphere. Also, the orders add
// up: the fluxes of orders <= 1, 2, 3 rise towards it with shrinking increments (the
// printed series shows the rest: ratios ~0.3 at tau 0.3 to ~0.6 at tau 0.9).
TEST(ReferenceSkyClosedForm, ConservativeLayerConservesEnergy) {
    const double Z = 10e3;
    const Atmosphere atm = homogeneous_layer(Z, {2e-5, 4e-5, 8e-5}, 1e-5, 1e-5, 0.0, 0.0);
    std::vector<double> x, w;
    gauss_legendre_unit(24, x, w);
    std::vector<glm::dvec3> up, down;
    for (double mu : x) {
        up.push_back({std::sqrt(1.0 - mu * mu), 0.0, mu});
        down.push_back({std::sqrt(1.0 - mu * mu), 0.0, -mu});
    }
    const Observer ground = sun_at(0.0), above = sun_at(0.0, Z + 1.0);
    const int n = 16384;
    auto flux = [&](int order, int paths_per_direction, std::vector<double>& se) {
        const ReferenceSky sky(paths(paths_per_direction, 17), order);
        const SkyRun a = run(sky, atm, ground, up), b = run(sky, atm, above, down);
        std::vector<double> f(3, 0.0);
        se.assign(3, 0.0);
        for (std::size_t i = 0; i < x.size(); ++i)
            for (std::size_t c = 0; c < 3; ++c) {
                const double k = kTwoPi * w[i] * x[i];
                f[c] += k * (a.radiance[i * 3 + c] + b.radiance[i * 3 + c]);
                se[c] += k * k *
                         (a.standard_error[i * 3 + c] * a.standard_error[i * 3 + c] +
                          b.standard_error[i * 3 + c] * b.standard_error[i * 3 + c]);
            }
        for (double& s : se) s = std::sqrt(s);
        return f;
    };
    std::vector<double> se, se_unused;
    const std::vector<double> all = flux(0, n, se);
    const std::vector<double> f1 = flux(1, 1, se_unused), f2 = flux(2, n / 4, se_unused),
                              f3 = flux(3, n / 4, se_unused);
    for (std::size_t c = 0; c < 3; ++c) {
        const double tau = (atm.rayleigh_scattering[c] + 1e-5) * Z;
        const double expected = -std::expm1(-tau);
        std::printf(
            "[ energy, tau %.1f ] F_up + F_down = %.6f, E (1 - e^-tau) = %.6f (%+.5f, se "
            "%.5f); orders <= 1, 2, 3: %.5f %.5f %.5f\n",
            tau, all[c], expected, all[c] / expected - 1.0, se[c] / expected, f1[c], f2[c], f3[c]);
        // 4 standard errors plus 5e-4 for the cosine quadrature and the planet's curvature.
        EXPECT_NEAR(all[c] / expected, 1.0, 4.0 * se[c] / expected + 5e-4);
        EXPECT_LT(f1[c], f2[c]);
        EXPECT_LT(f2[c], f3[c]);
        EXPECT_LT(f3[c], all[c]);
        EXPECT_LT(f3[c] - f2[c], f2[c] - f1[c]);
    }
    std::printf("[ energy ] %d paths per direction (orders 2 and 3: %d)\n", n, n / 4);
}

// ---------------------------------------------------------------------------------------
// Determinism: the same seed gives bit-identical output, whatever the thread count.
TEST(ReferenceSkyDeterminism, SameSeedSameOutputForAnyThreadCount) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const std::vector<glm::dvec3> dirs = {view_direction(0, 0), view_direction(60, 45),
                                          view_direction(85, 180), view_direction(95, 90)};
    const Observer obs = sun_at(50.0, 1500.0);
    const ReferenceSky sky(paths(2048, 42));
    const SkyRun a = run(sky, atm, obs, dirs), b = run(sky, atm, obs, dirs);
    SkyRun one_thread;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one_thread = run(sky, atm, obs, dirs);
    }
    const SkyRun other_seed = run(ReferenceSky(paths(2048, 43)), atm, obs, dirs);
    EXPECT_EQ(a.radiance, b.radiance);
    EXPECT_EQ(a.standard_error, b.standard_error);
    EXPECT_EQ(a.radiance, one_thread.radiance);
    EXPECT_EQ(a.standard_error, one_thread.standard_error);
    EXPECT_NE(a.radiance, other_seed.radiance);
}

// ---------------------------------------------------------------------------------------
// The edges of the domain: observers above the atmosphere, rays that miss it or hit the
// ground, the sun below the horizon, many wavelengths, other presets, bad arguments,
// progress and cancellation.
TEST(ReferenceSkyEdges, ObserverAboveTheAtmosphere) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const ReferenceSky sky(paths(1024));
    // 100 km up (the top is at 60 km): up and at the horizon the ray misses the air; down
    // it enters it, and 9.5 deg below the horizon it crosses the limb, grazing 11 km
    // above the ground (the top is tangent 6.3 deg below, the ground 10.2 deg): a long
    // path through dense air, brighter than straight down. From 36000 km, towards the
    // planet's centre.
    const std::vector<glm::dvec3> dirs = {view_direction(0, 0), view_direction(90, 0), view_direction(180, 0),
                                          view_direction(99.5, 0)};
    const SkyRun r = run(sky, atm, sun_at(30.0, 100e3), dirs);
    for (std::size_t c = 0; c < 3; ++c) {
        EXPECT_EQ(r.radiance[0 * 3 + c], 0.0f);
        EXPECT_EQ(r.standard_error[0 * 3 + c], 0.0f);
        EXPECT_EQ(r.radiance[1 * 3 + c], 0.0f);
        EXPECT_GT(r.radiance[2 * 3 + c], 0.0f);
        EXPECT_GT(r.radiance[3 * 3 + c], r.radiance[2 * 3 + c]);
        EXPECT_TRUE(std::isfinite(r.radiance[3 * 3 + c]));
    }
    const SkyRun far = run(sky, atm, sun_at(0.0, 36000e3), {view_direction(180, 0)});
    // Nadir from geostationary height, sun at the zenith: the path radiance of the whole
    // column, the same as seen from just above the top (the vacuum adds nothing).
    const SkyRun near = run(sky, atm, sun_at(0.0, 60e3 + 1.0), {view_direction(180, 0)});
    for (std::size_t c = 0; c < 3; ++c)
        EXPECT_NEAR(
            far.radiance[c] / near.radiance[c], 1.0,
            4.0 * std::hypot(far.standard_error[c], near.standard_error[c]) / near.radiance[c] + 1e-4);
}

TEST(ReferenceSkyEdges, GroundHittingRaysTwilightAndNight) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const ReferenceSky sky(paths(1024));
    const std::vector<glm::dvec3> dirs = {view_direction(0, 0), view_direction(80, 0), view_direction(120, 0),
                                          view_direction(180, 0)};
    double previous_zenith = 1e30;
    for (double sz : {80.0, 90.0, 96.0, 102.0, 120.0}) {
        const SkyRun r = run(sky, atm, sun_at(sz, 10e3), dirs);
        for (std::size_t i = 0; i < r.radiance.size(); ++i) {
            EXPECT_TRUE(std::isfinite(r.radiance[i])) << sz;
            EXPECT_GE(r.radiance[i], 0.0f) << sz;
            EXPECT_TRUE(std::isfinite(r.standard_error[i])) << sz;
        }
        // Down from 10 km: the air below carries light (no ground radiance is added).
        if (sz < 90.0) {
            EXPECT_GT(r.radiance[3 * 3 + 1], 0.0f);
        }
        // The zenith sky darkens as the sun sets and the Earth's shadow rises (once the
        // whole zenith ray is in the shadow, only rare multiply scattered paths light it).
        if (sz <= 96.0)
            EXPECT_LT(r.radiance[1], previous_zenith) << sz;
        else
            EXPECT_LE(r.radiance[1], previous_zenith) << sz;
        previous_zenith = r.radiance[1];
    }
}

TEST(ReferenceSkyEdges, SpectralModeAgreesWithThreeChannels) {
    // 48 wavelengths in one run (hero-wavelength paths): the channels at 680, 550 and
    // 440 nm match the three-channel run within their standard errors.
    const std::vector<double> w = spectral_wavelengths_nm();
    const Atmosphere spectral = Atmosphere::preset("bruneton2017", w);
    const Atmosphere rgb = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const std::vector<glm::dvec3> dirs = {view_direction(0, 0), view_direction(70, 90),
                                          view_direction(88, 0)};
    const int n = 8192;
    const SkyRun s = run(ReferenceSky(paths(n, 8)), spectral, sun_at(40.0), dirs);
    const SkyRun t = run(ReferenceSky(paths(n, 9)), rgb, sun_at(40.0), dirs);
    const std::size_t C = w.size();
    for (std::size_t i = 0; i < s.radiance.size(); ++i) {
        EXPECT_TRUE(std::isfinite(s.radiance[i]));
        EXPECT_GE(s.radiance[i], 0.0f);
    }
    const std::size_t at[3] = {std::size_t(std::find(w.begin(), w.end(), 680.0) - w.begin()),
                               std::size_t(std::find(w.begin(), w.end(), 550.0) - w.begin()),
                               std::size_t(std::find(w.begin(), w.end(), 440.0) - w.begin())};
    for (std::size_t i = 0; i < dirs.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const double a = s.radiance[i * C + at[c]], b = t.radiance[i * 3 + c];
            const double se = std::hypot(s.standard_error[i * C + at[c]], t.standard_error[i * 3 + c]);
            EXPECT_NEAR(a, b, 4.5 * se + 1e-6 * b) << "direction " << i << " " << kBands[c];
        }
}

TEST(ReferenceSkyEdges, EveryPresetGivesFinitePositiveSkies) {
    const std::vector<glm::dvec3> dirs = {view_direction(0, 0), view_direction(89, 0),
                                          view_direction(89, 180)};
    for (const std::string& name : Atmosphere::preset_names()) {
        const Atmosphere atm = Atmosphere::preset(name);
        const SkyRun r = run(ReferenceSky(paths(512)), atm, sun_at(45.0), dirs);
        for (std::size_t i = 0; i < r.radiance.size(); ++i) {
            EXPECT_TRUE(std::isfinite(r.radiance[i])) << name;
            EXPECT_GT(r.radiance[i], 0.0f) << name;
            EXPECT_LT(r.standard_error[i], 0.1f * r.radiance[i]) << name;
        }
    }
}

TEST(ReferenceSkyEdges, BadArgumentsNameTheParameter) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const ReferenceSky sky(paths(16));
    const std::vector<glm::dvec3> dirs = {view_direction(0, 0), glm::dvec3(0.0)};
    std::vector<float> out(6), se(6), short_out(5);
    auto parameter_of = [](auto&& f) {
        try {
            f();
        } catch (const InvalidArgument& e) {
            return e.parameter();
        }
        return std::string("(nothing thrown)");
    };
    EXPECT_EQ(parameter_of([&] { sky.radiance(atm, sun_at(0), dirs, out, se); }), "view_directions[1]");
    const std::vector<glm::dvec3> good = {view_direction(0, 0), view_direction(10, 0)};
    EXPECT_EQ(parameter_of([&] { sky.radiance(atm, sun_at(0), good, short_out); }), "out");
    EXPECT_EQ(parameter_of([&] { sky.radiance(atm, sun_at(0), good, out, short_out); }), "standard_error");
    EXPECT_EQ(parameter_of([&] { ReferenceSky bad(paths(16), -1); }), "max_scattering_order");
    EXPECT_EQ(parameter_of([&] { ReferenceSky bad(paths(0)); }), "reference_paths");
    EXPECT_EQ(make_sky_method("reference")->name(), "reference");
}

TEST(ReferenceSkyEdges, ReportsProgressAndCancels) {
    struct Recorder : Progress {
        std::vector<double> seen;
        int cancel_after = -1;
        bool report(double f) override {
            seen.push_back(f);
            return cancel_after < 0 || int(seen.size()) <= cancel_after;
        }
    };
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    std::vector<glm::dvec3> dirs;
    for (int i = 0; i < 40; ++i) dirs.push_back(view_direction(2.0 * i, 10.0 * i));
    std::vector<float> out(dirs.size() * 3);
    Recorder ok;
    ReferenceSky(paths(256)).radiance(atm, sun_at(30), dirs, out, {}, &ok);
    ASSERT_FALSE(ok.seen.empty());
    EXPECT_EQ(ok.seen.front(), 0.0);
    EXPECT_EQ(ok.seen.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(ok.seen.begin(), ok.seen.end()));
    Recorder stop;
    stop.cancel_after = 3;
    EXPECT_THROW(ReferenceSky(paths(256)).radiance(atm, sun_at(30), dirs, out, {}, &stop), Cancelled);
}

TEST(ReferenceSkyEdges, TwilightSingleScatteringMatchesBruteForce) {
    // Sun below the horizon: the view ray enters and leaves the Earth's shadow; the
    // method cuts its quadrature there. A 200000-step trapezoid agrees (the integrand
    // fades to ~0 at the shadow's edge, where the sun grazes the whole atmosphere).
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const ColumnTable table(atm);
    const ReferenceSky single(paths(1), 1);
    for (double sz : {93.0, 97.0})
        for (double altitude : {0.0, 10e3})
            for (const glm::dvec3& v : {view_direction(0, 0), view_direction(80, 0), view_direction(80, 180),
                                        view_direction(89, 30)}) {
                const Observer obs = sun_at(sz, altitude);
                const SkyRun r = run(single, atm, obs, {v});
                const std::vector<double> t =
                    trapezoid_single_scattering(atm, table, altitude, v, obs.sun_direction, 200000);
                for (std::size_t c = 0; c < 3; ++c)
                    EXPECT_NEAR(r.radiance[c], t[c], 1e-4 * t[c] + 1e-12)
                        << "sun " << sz << " altitude " << altitude << " view " << v.x << " " << v.z << " "
                        << kBands[c];
            }
}
