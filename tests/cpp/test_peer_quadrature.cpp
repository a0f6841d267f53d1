// SPDX-License-Identifier: Apache-2.0
// Where the peer table itself is inexact, shown rather than assumed.
//
// Bruneton 2017's reference ComputeSingleScattering integrates along the view ray with the
// trapezoid rule on 50 equal intervals. On a steep ray through the Mie layer (scale height
// 1.2 km) an interval is about one scale height long, and the trapezoid rule overestimates
// the integral of exp(-x / H) over steps of h by (h / 2H) coth(h / 2H) - 1: 8 % for
// h = H. So the peer's single Mie scattering, and with it its L1 and L columns, is too
// high where Mie dominates (towards the sun, at 680 nm).
//
// This test evaluates single scattering independently (exact double-precision
// transmittance from optical_depth.hpp, Welkin's phase functions) twice: with the peer's
// 50-interval trapezoid it must reproduce the peer's L1d column to 0.5 % on every view above
// the horizon, and with a converged quadrature it gives the true single scattering, which
// the other tests use to separate the peer's quadrature error from ours. It prints both.
#include <cstdio>

#include "peer_single_scattering.hpp"
#include "peer_table.hpp"
#include <gtest/gtest.h>

using namespace welkin;

TEST(PeerQuadrature, FiftyIntervalTrapezoidReproducesThePeersSingleScattering) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const char* columns[] = {"L1d_680nm", "L1d_550nm", "L1d_440nm"};
    std::vector<double> err_trap[3], bias[3];
    for (const auto& row : welkin::test::read_peer_table()) {
        if (row["view_zenith_deg"] >= 90.0) continue;
        const auto trap = welkin::test::single_scattering(atm, row, 50);
        const auto exact = welkin::test::single_scattering(atm, row, 1000);
        for (int c = 0; c < 3; ++c) {
            const double peer = row[columns[c]];
            err_trap[c].push_back(std::abs(trap[c] / peer - 1.0));
            bias[c].push_back(peer / exact[c] - 1.0);
            EXPECT_LT(std::abs(trap[c] / peer - 1.0), 0.005)
                << columns[c] << " sun " << row["sun_zenith_deg"] << " view " << row["view_zenith_deg"];
        }
    }
    for (int c = 0; c < 3; ++c) {
        const auto [m, w] = welkin::test::median_and_max(err_trap[c]);
        const auto [bm, bw] = welkin::test::median_and_max(bias[c]);
        std::printf(
            "%s: 50-interval trapezoid vs peer median %.2f %% worst %.2f %%; peer minus converged "
            "single scattering: median %+.2f %%, largest %+.2f %%\n",
            columns[c], 100 * m, 100 * w, 100 * bm, 100 * bw);
    }
}
