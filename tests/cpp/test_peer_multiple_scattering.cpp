// SPDX-License-Identifier: Apache-2.0
// Why the peer's orders 2-4 differ from ours, shown rather than assumed, and the
// comparisons with the peer made like for like.
//
// The finding. Welkin's `reference` path tracer truncated to 4 orders matches the peer
// table within 1.4 % with the sun at the zenith but only within ~5 % (7 % at 440 nm) at sun
// zenith 30 and 60 degrees, where the peer's orders 2-4 (its L - L1 columns) are up to
// 1.24x ours towards the sun and 0.81x away from it. Three errors on the peer's side,
// each measured:
//  * its texture lookup (peer_texture_lookup.hpp): near the zenith the mu axis has texels
//    at 0 and 39 degrees only, the zenith texel's nu is clamped to mu_s in every nu slice,
//    and the multiple-scattering texels are stored divided by the Rayleigh phase of their
//    own clamped nu and multiplied back by that of the view. This makes the azimuthal
//    structure: passing the reference's own orders 2-4, evaluated at the texels'
//    geometries, through the same lookup reproduces the peer's L - L1 to about 1 % of L
//    (2.4 % at the horizon at 680 nm), towards and away from the sun alike.
//  * the quadratures of its second order (peer_second_order.hpp: 16 x 32 midpoint
//    directions in ComputeScatteringDensity, 50-interval trapezoids along the rays, J
//    interpolated on 8 nu samples). They hardly change the azimuthal structure
//    (PeerQuadraturesDoNotMakeTheAzimuthalStructure) but they are the horizon residual:
//    the incoming light of J has a bright band at the horizon and an edge where the ground
//    begins, which the midpoint rule's 11.25-degree zenith cells straddle, so J and the
//    second order come out low where that band dominates: at sun 60, view 89, az 90 the
//    peer's rules give a second order 5.8 % below the reference's at 680 nm, 1.35 % of L
//    (the midpoint rule over the sphere alone: about -7.8 %; with 24 and 48 zenith cells
//    still -4.6 and -2.1 %; the same rule converges to the reference at sun 30, view 60,
//    where there is no such band). Computed at the
//    view under the peer's rules (its final nu lookup left to the texture lookup above)
//    minus the reference's second order (16384 paths), that error is `second order's
//    quadratures` below; with it, the reference like for like is within 1.3 % everywhere.
//  * its 50-interval single scattering (test_peer_quadrature.cpp).
// Not emulated, and what remains (mostly +0.5..1.3 % of L at the horizon at 550-680 nm,
// ours brighter): the same quadratures in the peer's orders 3 and 4 (its J_3, J_4 use the
// same 16 x 32 rule; those orders are about 15 % of its orders 2-4 there), the quadrature error
// read through the texture lookup rather than at the view, and the peer's
// in-precomputation textures (transmittance 256 x 64, irradiance 64 x 16, the 4D J and
// L_n read by interpolation inside the precomputation).
//
// What is asserted, in TextureLookupExplainsThePeerLikeForLike (4096 paths per direction
// for orders 2-4, relative standard error of the multiple-scattering part under 1 %; 16384
// for the second order at the views):
//  1. The peer's orders 2-4 through its texture lookup: for every view above the horizon at
//     sun zenith 0, 30 and 60 degrees, |emulated - peer| of the orders 2-4 within 2.5 % of
//     L (measured worst 1.5 / 1.5 / 2.4 % at sun 0 / 30 / 60; the raw reference is up to
//     7.1 % off at 440 nm, sun 30), and the emulated ratio of the orders 2-4 towards / away
//     from the sun within 5 % of the peer's at every view zenith (measured: peer 1.38-1.46
//     at sun 30, views 30-60, emulated 1.40-1.44, reference 1.04-1.05; worst mismatch 4 %
//     at sun 60, view 60, 680 nm, where the peer's ratio is only 1.05).
//  2. The reference like for like: the reference with the peer's three errors put in (its
//     50-interval single scattering, the texture lookup of its orders 2-4 and the
//     quadratures of its second order) within 2 % of the peer's L for every view
//     at sun zenith 0, 30 and 60 degrees. Measured worst 1.31 / 1.17 / 1.13 %, median
//     0.18-0.50 %; with the first two errors only: worst 1.54 / 1.54 / 2.39 %.
//  3. `lut` against the peer with the three errors taken out (peer L minus the emulated
//     errors): median within 2.5 %, worst within 5 % (measured median
//     1.1 / 1.1 / 1.7 %, worst 3.9 / 2.8 / 4.7 % at 680 / 550 / 440 nm).
// WELKIN_PEER_DUMP=1 prints every row.
//
// Runtime: about 25-35 s on two loaded cores (the reference at 266 view and texel
// directions, 4096 paths each; the peer's second-order rules at the 58 distinct views).
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "peer_second_order.hpp"
#include "peer_single_scattering.hpp"
#include "peer_table.hpp"
#include "peer_texture_lookup.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <oneapi/tbb/parallel_for.h>

#include "welkin/sky/method.hpp"
#include "welkin/sky/reference.hpp"

using namespace welkin;
using welkin::test::PeerRow;
using welkin::test::PeerTexel;

namespace {

const char* const kNames[] = {"680nm", "550nm", "440nm"};

// The view direction (Welkin's frame, sun at azimuth 0) a texel stands for.
glm::dvec3 texel_view(const PeerTexel& t) {
    const double st = std::sqrt(std::max(0.0, 1 - t.mu * t.mu));
    const double ss = std::sqrt(std::max(0.0, 1 - t.mu_s * t.mu_s));
    const double c = (st > 0 && ss > 0) ? std::clamp((t.nu - t.mu * t.mu_s) / (st * ss), -1.0, 1.0) : 1.0;
    return {st * c, st * std::sqrt(std::max(0.0, 1 - c * c)), t.mu};
}

// Everything the three tests compare, per peer row above the horizon.
struct Row {
    PeerRow peer;
    std::array<double, 3> ms_ref, ms_emulated, ss_trap50, ss_exact, lut;
    // The peer's quadrature error in its second order at the view: L_2 under the peer's
    // rules (peer_second_order.hpp, its final nu lookup left to ms_emulated) minus the
    // reference's second order.
    std::array<double, 3> second_order_quadrature;
};

// The reference's orders 2..last (`last` orders minus the exact single scattering) at a set
// of directions for one sun, deduplicated.
class OrdersTwoToFour {
public:
    explicit OrdersTwoToFour(int last = 4) : last_(last) {}
    void add(double mu_s, const glm::dvec3& v) {
        auto& d = dirs_[mu_s];
        for (const glm::dvec3& x : d)
            if (glm::length(x - v) < 1e-12) return;
        d.push_back(v);
    }
    void run(const Atmosphere& atm, int paths) {
        for (auto& [mu_s, d] : dirs_) {
            const Observer obs{0.0, glm::dvec3(std::sqrt(std::max(0.0, 1 - mu_s * mu_s)), 0.0, mu_s)};
            std::vector<float> four(d.size() * 3), one(d.size() * 3);
            SkyOptions o;
            o.reference_paths = paths;
            o.seed = 17;
            ReferenceSky(o, last_).radiance(atm, obs, d, four);
            SkyOptions single;
            single.reference_paths = 1;
            ReferenceSky(single, 1).radiance(atm, obs, d, one);
            auto& out = values_[mu_s];
            for (std::size_t i = 0; i < four.size(); ++i) out.push_back(double(four[i]) - double(one[i]));
        }
    }
    std::array<double, 3> at(double mu_s, const glm::dvec3& v) const {
        const auto& d = dirs_.at(mu_s);
        for (std::size_t i = 0; i < d.size(); ++i)
            if (glm::length(d[i] - v) < 1e-12) {
                const auto& x = values_.at(mu_s);
                return {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
            }
        ADD_FAILURE() << "direction not computed";
        return {0, 0, 0};
    }
    std::size_t size() const {
        std::size_t n = 0;
        for (const auto& [k, d] : dirs_) n += d.size();
        return n;
    }

private:
    int last_;
    std::map<double, std::vector<glm::dvec3>> dirs_;
    std::map<double, std::vector<double>> values_;
};

const std::vector<Row>& rows() {
    static const std::vector<Row> out = [] {
        const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
        const welkin::test::PeerGroundTexture texture(atm);
        std::vector<Row> r;
        OrdersTwoToFour ms, second(2);
        for (const PeerRow& p : welkin::test::read_peer_table()) {
            if (!(p["view_zenith_deg"] < 90.0)) continue;
            const glm::dvec3 s = p.sun_direction(), v = p.view_direction();
            ms.add(s.z, v);
            for (const PeerTexel& t : texture.texels(v.z, s.z, glm::dot(v, s))) ms.add(t.mu_s, texel_view(t));
            second.add(s.z, v);
            r.push_back({p, {}, {}, {}, {}, {}, {}});
        }
        ms.run(atm, 4096);
        second.run(atm, 16384);
        std::printf("[ peer lookup ] reference orders 2-4 at %zu directions (views and texels)\n", ms.size());
        // The second order under the peer's rules, once per distinct geometry.
        const welkin::test::SecondOrder quadrature(atm);
        welkin::test::SecondOrderRules peer_rules = welkin::test::SecondOrderRules::peer();
        peer_rules.final_lookup = false;
        std::vector<welkin::test::Rgb> peer_second(r.size());
        std::vector<int> same(r.size());
        for (std::size_t i = 0; i < r.size(); ++i) {
            same[i] = int(i);
            for (std::size_t j = 0; j < i; ++j)
                if (r[j].peer.sun_direction() == r[i].peer.sun_direction() &&
                    glm::length(r[j].peer.view_direction() - r[i].peer.view_direction()) < 1e-12) {
                    same[i] = int(j);
                    break;
                }
        }
        tbb::parallel_for(0, int(r.size()), [&](int i) {
            if (same[std::size_t(i)] != i) return;
            const glm::dvec3 s = r[std::size_t(i)].peer.sun_direction(),
                             v = r[std::size_t(i)].peer.view_direction();
            peer_second[std::size_t(i)] =
                quadrature.radiance(atm.bottom_radius_m, v.z, s.z, glm::dot(v, s), peer_rules);
        });
        const auto lut = make_sky_method("lut");
        for (std::size_t i = 0; i < r.size(); ++i) {
            Row& row = r[i];
            const auto ref2 = second.at(row.peer.sun_direction().z, row.peer.view_direction());
            for (int c = 0; c < 3; ++c)
                row.second_order_quadrature[std::size_t(c)] =
                    peer_second[std::size_t(same[i])][std::size_t(c)] - ref2[std::size_t(c)];
        }
        for (Row& row : r) {
            const glm::dvec3 s = row.peer.sun_direction(), v = row.peer.view_direction();
            row.ms_ref = ms.at(s.z, v);
            row.ms_emulated = texture.rayleigh_normalised_lookup(
                v.z, s.z, glm::dot(v, s), [&](const PeerTexel& t) { return ms.at(t.mu_s, texel_view(t)); });
            row.ss_trap50 = welkin::test::single_scattering(atm, row.peer, 50);
            row.ss_exact = welkin::test::single_scattering(atm, row.peer, 1000);
            const SkyResult l = sky_radiance(*lut, atm, Observer{0.0, s}, std::vector<glm::dvec3>{v});
            for (int c = 0; c < 3; ++c) row.lut[std::size_t(c)] = l.radiance[std::size_t(c)];
        }
        return r;
    }();
    return out;
}

double peer(const Row& r, const char* prefix, int c) { return r.peer[std::string(prefix) + kNames[c]]; }
int sun_index(const Row& r) { return int(r.peer["sun_zenith_deg"] / 30.0 + 0.5); }

std::pair<double, double> abs_median_max(std::vector<double> x) {
    for (double& y : x) y = std::abs(y);
    return welkin::test::median_and_max(x);
}

}  // namespace

namespace {

void texture_lookup_reproduces_the_peers_orders_two_to_four() {
    std::vector<double> raw[3][3], emulated[3][3];
    for (const Row& r : rows())
        for (int c = 0; c < 3; ++c) {
            const double L = peer(r, "L_", c), ms = L - peer(r, "L1_", c);
            raw[sun_index(r)][c].push_back((r.ms_ref[c] - ms) / L);
            emulated[sun_index(r)][c].push_back((r.ms_emulated[c] - ms) / L);
            EXPECT_LT(std::abs(r.ms_emulated[c] - ms) / L, 0.025)
                << kNames[c] << " sun " << r.peer["sun_zenith_deg"] << " view " << r.peer["view_zenith_deg"]
                << " az " << r.peer["rel_azimuth_deg"];
        }
    for (int g = 0; g < 3; ++g)
        for (int c = 0; c < 3; ++c) {
            const auto [rm, rw] = abs_median_max(raw[g][c]);
            const auto [em, ew] = abs_median_max(emulated[g][c]);
            std::printf(
                "[ peer orders 2-4, sun %2d, %s ] reference vs peer: median %.2f %% worst %.2f %% of L; "
                "through the peer's texture lookup: median %.2f %% worst %.2f %%\n",
                30 * g, kNames[c], 100 * rm, 100 * rw, 100 * em, 100 * ew);
        }
    // Towards (az 0) over away (az 180) from the sun, per sun and view zenith.
    for (const Row& a : rows()) {
        if (a.peer["rel_azimuth_deg"] != 0.0 || a.peer["sun_zenith_deg"] == 0.0 ||
            a.peer["view_zenith_deg"] == 0.0)
            continue;
        for (const Row& b : rows()) {
            if (b.peer["rel_azimuth_deg"] != 180.0 || b.peer["sun_zenith_deg"] != a.peer["sun_zenith_deg"] ||
                b.peer["view_zenith_deg"] != a.peer["view_zenith_deg"])
                continue;
            std::printf("[ towards/away, sun %2.0f view %2.0f ]", a.peer["sun_zenith_deg"],
                        a.peer["view_zenith_deg"]);
            for (int c = 0; c < 3; ++c) {
                const double p =
                    (peer(a, "L_", c) - peer(a, "L1_", c)) / (peer(b, "L_", c) - peer(b, "L1_", c));
                const double e = a.ms_emulated[c] / b.ms_emulated[c], d = a.ms_ref[c] / b.ms_ref[c];
                std::printf("  %s peer %.3f lookup %.3f reference %.3f", kNames[c], p, e, d);
                EXPECT_LT(std::abs(e / p - 1.0), 0.05) << kNames[c];
            }
            std::printf("\n");
        }
    }
}

void reference_like_for_like() {
    std::vector<double> err[3][3], before[3][3], raw[3][3];
    for (const Row& r : rows())
        for (int c = 0; c < 3; ++c) {
            const double L = peer(r, "L_", c);
            const double lookup_only = r.ss_trap50[c] + r.ms_emulated[c];
            const double like = lookup_only + r.second_order_quadrature[c];
            before[sun_index(r)][c].push_back(lookup_only / L - 1.0);
            raw[sun_index(r)][c].push_back((r.ss_exact[c] + r.ms_ref[c]) / L - 1.0);
            err[sun_index(r)][c].push_back(like / L - 1.0);
            if (std::getenv("WELKIN_PEER_DUMP"))
                std::printf(
                    "[ row ] sun %2.0f view %2.0f az %3.0f %s: reference %+.2f %%, lookup %+.2f %%, "
                    "+ second-order quadratures %+.2f %% of L\n",
                    r.peer["sun_zenith_deg"], r.peer["view_zenith_deg"], r.peer["rel_azimuth_deg"], kNames[c],
                    100 * ((r.ss_exact[c] + r.ms_ref[c]) / L - 1), 100 * (lookup_only / L - 1),
                    100 * (like / L - 1));
            EXPECT_LT(std::abs(like / L - 1.0), 0.02)
                << kNames[c] << " sun " << r.peer["sun_zenith_deg"] << " view " << r.peer["view_zenith_deg"]
                << " az " << r.peer["rel_azimuth_deg"];
        }
    for (int g = 0; g < 3; ++g)
        for (int c = 0; c < 3; ++c) {
            const auto [rm, rw] = abs_median_max(raw[g][c]);
            const auto [bm, bw] = abs_median_max(before[g][c]);
            const auto [m, w] = abs_median_max(err[g][c]);
            std::printf(
                "[ reference vs peer, sun %2d, %s ] raw (4 orders): median %.2f %% worst %.2f %%; "
                "like for like, lookup only: median %.2f %% worst %.2f %%; "
                "with the second order's quadratures: median %.2f %% worst %.2f %%\n",
                30 * g, kNames[c], 100 * rm, 100 * rw, 100 * bm, 100 * bw, 100 * m, 100 * w);
        }
}

void lut_against_the_peer_corrected() {
    std::vector<double> err[3], lookup_only[3];
    for (const Row& r : rows())
        for (int c = 0; c < 3; ++c) {
            // The peer with its measured errors taken out: single scattering, texture
            // lookup, and the quadratures of its second order.
            const double two =
                peer(r, "L_", c) - (r.ss_trap50[c] - r.ss_exact[c]) - (r.ms_emulated[c] - r.ms_ref[c]);
            const double corrected = two - r.second_order_quadrature[c];
            lookup_only[c].push_back(r.lut[c] / two - 1.0);
            err[c].push_back(r.lut[c] / corrected - 1.0);
        }
    for (int c = 0; c < 3; ++c) {
        const auto [m, w] = abs_median_max(err[c]);
        const auto [m2, w2] = abs_median_max(lookup_only[c]);
        std::printf(
            "[ lut vs peer corrected, %s ] median %.2f %% worst %.2f %% (%zu views); "
            "without the second-order quadratures: median %.2f %% worst %.2f %%\n",
            kNames[c], 100 * m, 100 * w, err[c].size(), 100 * m2, 100 * w2);
        EXPECT_LT(m, 0.025) << kNames[c];
        EXPECT_LT(w, 0.05) << kNames[c];
    }
}

}  // namespace

// One test for the three, which share the reference run (ctest runs each test in its own
// process).
TEST(PeerMultipleScattering, TextureLookupExplainsThePeerLikeForLike) {
    {
        SCOPED_TRACE("the peer's orders 2-4 through its texture lookup");
        texture_lookup_reproduces_the_peers_orders_two_to_four();
    }
    {
        SCOPED_TRACE("reference like for like");
        reference_like_for_like();
    }
    {
        SCOPED_TRACE("lut against the peer corrected");
        lut_against_the_peer_corrected();
    }
}

// The first candidate, refuted: the peer's quadratures of its second order. At the view
// with the strongest azimuthal structure (sun zenith 30, view zenith 60, towards and away
// from the sun), the second order by deterministic quadrature (peer_second_order.hpp),
// converged and with all of the peer's rules together, against the reference's second
// order (16384 paths). Asserted: (a) the converged quadrature agrees with the reference's
// second order within 1.5 % (measured 0.0-0.3 %), which validates the machinery; (b) with
// the peer's rules the towards/away ratio of the second order moves by less than 10 %
// (measured +7.6-8.0 %: +5.8..+6.4 % towards, -1.1..-1.8 % away), while the peer's orders
// 2-4 are 1.43-1.46 against the converged 1.03-1.04 (asserted: more than 25 % above it).
// So the quadratures are a minor part of the azimuthal structure; the texture lookup
// (above) is its cause. (They are not minor at the horizon, where the midpoint rule over
// the sphere misses the bright horizon band: see the file's header. This converged rule,
// 24 x 48 midpoint directions, is converged here but not there.)
// Runtime about 12 s on two loaded cores.
TEST(PeerMultipleScattering, PeerQuadraturesDoNotMakeTheAzimuthalStructure) {
    using welkin::test::SecondOrderRules;
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const welkin::test::SecondOrder second(atm);
    const SecondOrderRules converged{0, 24, 0, false}, peer_rules = SecondOrderRules::peer();
    std::vector<const PeerRow*> views;
    const auto table = welkin::test::read_peer_table();
    for (const PeerRow& p : table)
        if (p["sun_zenith_deg"] == 30.0 && p["view_zenith_deg"] == 60.0 &&
            (p["rel_azimuth_deg"] == 0.0 || p["rel_azimuth_deg"] == 180.0))
            views.push_back(&p);
    ASSERT_EQ(views.size(), 2u);
    std::array<welkin::test::Rgb, 4> det{};  // [view][converged, peer]
    tbb::parallel_for(0, 4, [&](int k) {
        const PeerRow& p = *views[std::size_t(k / 2)];
        const glm::dvec3 s = p.sun_direction(), v = p.view_direction();
        det[std::size_t(k)] =
            second.radiance(atm.bottom_radius_m, v.z, s.z, glm::dot(v, s), k % 2 ? peer_rules : converged);
    });
    std::array<std::array<double, 3>, 2> ref{};
    for (std::size_t i = 0; i < 2; ++i) {
        const glm::dvec3 s = views[i]->sun_direction(), v = views[i]->view_direction();
        std::vector<float> two(3), one(3);
        SkyOptions o;
        o.reference_paths = 16384;
        o.seed = 23;
        ReferenceSky(o, 2).radiance(atm, Observer{0.0, s}, std::vector<glm::dvec3>{v}, two);
        SkyOptions single;
        single.reference_paths = 1;
        ReferenceSky(single, 1).radiance(atm, Observer{0.0, s}, std::vector<glm::dvec3>{v}, one);
        for (int c = 0; c < 3; ++c)
            ref[i][std::size_t(c)] = double(two[std::size_t(c)]) - double(one[std::size_t(c)]);
    }
    for (int c = 0; c < 3; ++c) {
        for (std::size_t i = 0; i < 2; ++i) {
            const double conv = det[2 * i][std::size_t(c)], peer = det[2 * i + 1][std::size_t(c)];
            std::printf(
                "[ second order, sun 30 view 60 az %3.0f, %s ] reference %.4e, converged quadrature %+.2f "
                "%%, "
                "peer's rules %+.2f %%\n",
                (*views[i])["rel_azimuth_deg"], kNames[c], ref[i][std::size_t(c)],
                100 * (conv / ref[i][std::size_t(c)] - 1), 100 * (peer / conv - 1));
            EXPECT_LT(std::abs(conv / ref[i][std::size_t(c)] - 1), 0.015) << kNames[c];
        }
        const double conv_ratio = det[0][std::size_t(c)] / det[2][std::size_t(c)];
        const double peer_ratio = det[1][std::size_t(c)] / det[3][std::size_t(c)];
        const double table_ratio =
            ((*views[0])[std::string("L_") + kNames[c]] - (*views[0])[std::string("L1_") + kNames[c]]) /
            ((*views[1])[std::string("L_") + kNames[c]] - (*views[1])[std::string("L1_") + kNames[c]]);
        std::printf(
            "[ second order towards/away, %s ] converged %.3f, peer's rules %.3f; the peer's orders 2-4 "
            "%.3f\n",
            kNames[c], conv_ratio, peer_ratio, table_ratio);
        EXPECT_LT(std::abs(peer_ratio / conv_ratio - 1), 0.10) << kNames[c];
        EXPECT_GT(table_ratio / conv_ratio - 1, 0.25) << kNames[c];
    }
}

// The tabulated sun optical depth the second-order quadratures use (peer_second_order.hpp,
// SunOpticalDepth) against the column table it is built from, on a grid of altitudes and
// zenith cosines offset from its nodes: transmittances within 1e-3 (measured 5.9e-4 at
// worst, near the horizon).
TEST(PeerMultipleScattering, SecondOrderSunTable) {
    const Atmosphere atm = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    const welkin::test::SecondOrder second(atm);
    double worst = 0;
    for (int i = 0; i <= 300; ++i)
        for (int j = 0; j <= 1000; ++j) {
            const double r =
                atm.bottom_radius_m + (atm.top_radius_m - atm.bottom_radius_m) * std::pow(i / 300.0, 2.0);
            const double mu = -0.2 + 1.2 * (j + 0.37) / 1001.0;
            if (ray_hits_ground(r, mu, atm.bottom_radius_m)) continue;
            double tau[3];
            second.sun_optical_depth()(r, mu, tau);
            const ColumnDensity col = second.table().to_top(r, mu);
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, std::abs(std::exp(-tau[c]) - std::exp(-optical_depth(atm, c, col))));
        }
    std::printf("[ sun optical-depth table ] worst |T - T_column_table| %.2e\n", worst);
    EXPECT_LT(worst, 1e-3);
}
