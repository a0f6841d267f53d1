// SPDX-License-Identifier: Apache-2.0
// The fast methods against the peer table (Bruneton 2017's double-precision spectral
// reference, 4 scattering orders): views above the horizon, 680/550/440 nm.
//
// The peer's single scattering carries its own quadrature error (test_peer_quadrature.cpp:
// up to +6.4 % towards the sun at 680 nm), so the comparison is made against the peer with
// its single-scattering part replaced by the converged one, L - L1d + SS_converged; the raw
// figures are printed too.
//
// Tolerances. The target for lut is 5 %. Measured (multiple-scattering LUT with the
// dipole and quadrupole of the multiply-scattered light, multiscattering_lut.hpp): lut
// median 1.5 / 1.4 / 2.0 %, worst 5.2 / 6.6 / 9.7 % at 680 / 550 / 440 nm; raymarch
// median 1.1 / 1.2 / 1.7 %, worst 5.1 / 6.3 / 9.5 %. Asserted: median within 2.5 %, worst
// within 6 / 7 / 10 %. The worst views are not the methods' error: at each of them the
// reference path tracer (all orders) is itself 3.6 / 5.4 / 9.0 % above the peer, because the
// peer's orders 2-4 have an azimuthal structure (up to 1.38x brighter towards the sun than
// away from it at 440 nm) that the reference does not have and whose second order an
// independent quadrature confirms (test_multiscattering_vs_reference.cpp prints these; there
// lut is within 5 % of the reference for every view, which is asserted). That structure is
// the peer's 4D-texture lookup (test_peer_multiple_scattering.cpp, which also asserts lut
// within 5 % of the peer with that error and the single-scattering one taken out). Before the
// extension (Hillaire's isotropic term) lut measured median 1.6 / 2.3 / 3.3 %, worst
// 6.1 / 7.1 / 10.3 % here. The analytic method (single scattering only) is held to the
// peer's single scattering within 25 %, its measured envelope.
#include <array>
#include <cstdio>

#include "peer_single_scattering.hpp"
#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/sky/method.hpp"

using namespace welkin;
using welkin::test::PeerRow;

namespace {

const char* kNames[] = {"680nm", "550nm", "440nm"};

struct Errors {
    std::vector<double> raw[3], corrected[3];
};

// `single_only`: compare with the converged single scattering instead of all orders.
Errors relative_errors(const std::string& method, bool single_only = false) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const auto sky = make_sky_method(method);
    Errors e;
    for (double sun_zenith : {0.0, 30.0, 60.0}) {
        std::vector<PeerRow> rows;
        std::vector<glm::dvec3> dirs;
        for (const PeerRow& row : welkin::test::read_peer_table())
            if (row["sun_zenith_deg"] == sun_zenith && row["view_zenith_deg"] < 90.0) {
                rows.push_back(row);
                dirs.push_back(row.view_direction());
            }
        EXPECT_FALSE(rows.empty());
        const SkyResult r = sky_radiance(*sky, atm, Observer{0.0, rows.front().sun_direction()}, dirs);
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const auto ss = welkin::test::single_scattering(atm, rows[i], 1000);
            for (int c = 0; c < 3; ++c) {
                const std::string n = kNames[c];
                const double raw = single_only ? rows[i]["L1d_" + n] : rows[i]["L_" + n];
                const double corrected = single_only ? ss[c] : raw - rows[i]["L1d_" + n] + ss[c];
                e.raw[c].push_back(std::abs(r.radiance[i * 3 + c] / raw - 1.0));
                e.corrected[c].push_back(std::abs(r.radiance[i * 3 + c] / corrected - 1.0));
            }
        }
    }
    for (int c = 0; c < 3; ++c) {
        const auto [m, w] = welkin::test::median_and_max(e.corrected[c]);
        const auto [rm, rw] = welkin::test::median_and_max(e.raw[c]);
        std::printf(
            "%-9s %s vs %s: median %.2f %% worst %.2f %% (raw peer: median %.2f %% worst %.2f %%), %zu "
            "views\n",
            method.c_str(), kNames[c], single_only ? "single scattering" : "peer (SS converged)", 100 * m,
            100 * w, 100 * rm, 100 * rw, e.corrected[c].size());
    }
    return e;
}

void expect_within(const Errors& e, double median_bound, const std::array<double, 3>& worst_bound) {
    for (int c = 0; c < 3; ++c) {
        const auto [median, worst] = welkin::test::median_and_max(e.corrected[c]);
        EXPECT_LT(median, median_bound) << kNames[c];
        EXPECT_LT(worst, worst_bound[std::size_t(c)]) << kNames[c];
    }
}

}  // namespace

TEST(FastMethodsVsPeer, Lut) { expect_within(relative_errors("lut"), 0.025, {0.06, 0.07, 0.10}); }

TEST(FastMethodsVsPeer, Raymarch) { expect_within(relative_errors("raymarch"), 0.025, {0.06, 0.07, 0.10}); }

TEST(FastMethodsVsPeer, AnalyticAgainstSingleScattering) {
    expect_within(relative_errors("analytic", true), 0.10, {0.25, 0.25, 0.25});
}
