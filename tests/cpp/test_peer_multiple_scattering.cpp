// Why the peer's orders 2-4 depend on the view azimuth more than ours, shown rather than
// assumed, and the comparisons with the peer made like for like.
//
// The finding. Welkin's `reference` path tracer truncated to 4 orders matches the peer
// table within 1.4 % with the sun at the zenith but only within ~5 % (7 % at 440 nm) at sun
// zenith 30 and 60 degrees, where the peer's orders 2-4 (its L - L1 columns) are up to
// 1.24x ours towards the sun and 0.81x away from it. Two candidates on the peer's side were
// measured with a deterministic second-order quadrature (peer_second_order.hpp), which
// agrees with the reference's second order to 0.5 % (2 % at the horizon):
//  * its quadratures (16 x 32 midpoint directions in ComputeScatteringDensity, 50-interval
//    trapezoids along the rays, 8 nu samples): they change the second order by -4.6 to
//    +6.3 %, mostly alike towards and away from the sun. Not the cause.
//  * its texture lookup (peer_texture_lookup.hpp): near the zenith the mu axis has texels
//    at 0 and 39 degrees only, the zenith texel's nu is clamped to mu_s in every nu slice,
//    and the multiple-scattering texels are stored divided by the Rayleigh phase of their
//    own clamped nu and multiplied back by that of the view. This is the cause: passing
//    the reference's own orders 2-4, evaluated at the texels' geometries, through the same
//    lookup reproduces the peer's L - L1 to about 1 % of L (2.4 % at the horizon at
//    680 nm), towards and away from the sun alike (printed below).
//
// What is asserted, in TextureLookupExplainsThePeerLikeForLike (4096 paths per direction;
// relative standard error of the multiple-scattering part under 1 %):
//  1. The peer's orders 2-4 through its texture lookup: for every view above the horizon at
//     sun zenith 0, 30 and 60 degrees, |emulated - peer| of the orders 2-4 within 2.5 % of
//     L (measured worst 1.5 / 1.5 / 2.4 % at sun 0 / 30 / 60; the raw reference is up to
//     7.1 % off at 440 nm, sun 30), and the emulated ratio of the orders 2-4 towards / away
//     from the sun within 5 % of the peer's at every view zenith (measured: peer 1.38-1.46
//     at sun 30, views 30-60, emulated 1.40-1.44, reference 1.04-1.05; worst mismatch 4 %
//     at sun 60, view 60, 680 nm, where the peer's ratio is only 1.05).
//  2. The reference like for like: the reference with the peer's two errors put in, its
//     50-interval single scattering and the texture lookup of its orders 2-4, within 2 % of
//     the peer's L for every view at sun zenith 0 and 30 degrees and within 2.5 % at 60
//     (measured worst 1.5 / 1.5 / 2.4 %). The 60-degree bound is above the 2 % issue #2 asks
//     for by the peer's residual at the horizon at 680 nm, which this emulation leaves (it
//     emulates the lookup at the camera only, not the textures inside the peer's
//     precomputation, whose quadratures alone move its second order by -4.6..+6.3 %).
//  3. `lut` against the peer with both errors taken out
//     (peer L minus the emulated errors): median within 2.5 %, worst within 5 % (issue #2;
//     measured median 1.3 / 1.2 / 1.6 %, worst 3.8 / 3.1 / 4.8 % at 680 / 550 / 440 nm).
//
// Runtime: about 9-12 s (the reference at 266 view and texel directions, 4096 paths each).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <map>

#include <glm/geometric.hpp>

#include <oneapi/tbb/parallel_for.h>

#include "peer_second_order.hpp"
#include "peer_single_scattering.hpp"
#include "peer_table.hpp"
#include "peer_texture_lookup.hpp"
#include "welkin/reference_sky.hpp"
#include "welkin/sky_method.hpp"

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
};

// The reference's orders 2-4 (4 orders minus the exact single scattering) at a set of
// directions for one sun, deduplicated.
class OrdersTwoToFour {
public:
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
            ReferenceSky(o, 4).radiance(atm, obs, d, four);
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
    std::map<double, std::vector<glm::dvec3>> dirs_;
    std::map<double, std::vector<double>> values_;
};

const std::vector<Row>& rows() {
    static const std::vector<Row> out = [] {
        const Atmosphere atm = Atmosphere::preset("bruneton2017");
        const welkin::test::PeerGroundTexture texture(atm);
        std::vector<Row> r;
        OrdersTwoToFour ms;
        for (const PeerRow& p : welkin::test::read_peer_table()) {
            if (!(p["view_zenith_deg"] < 90.0)) continue;
            const glm::dvec3 s = p.sun_direction(), v = p.view_direction();
            ms.add(s.z, v);
            for (const PeerTexel& t : texture.texels(v.z, s.z, glm::dot(v, s))) ms.add(t.mu_s, texel_view(t));
            r.push_back({p, {}, {}, {}, {}, {}});
        }
        ms.run(atm, 4096);
        std::printf("[ peer lookup ] reference orders 2-4 at %zu directions (views and texels)\n", ms.size());
        const auto lut = make_sky_method("lut");
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
            std::printf("[ peer orders 2-4, sun %2d, %s ] reference vs peer: median %.2f %% worst %.2f %% of L; "
                        "through the peer's texture lookup: median %.2f %% worst %.2f %%\n",
                        30 * g, kNames[c], 100 * rm, 100 * rw, 100 * em, 100 * ew);
        }
    // Towards (az 0) over away (az 180) from the sun, per sun and view zenith.
    for (const Row& a : rows()) {
        if (a.peer["rel_azimuth_deg"] != 0.0 || a.peer["sun_zenith_deg"] == 0.0 || a.peer["view_zenith_deg"] == 0.0)
            continue;
        for (const Row& b : rows()) {
            if (b.peer["rel_azimuth_deg"] != 180.0 || b.peer["sun_zenith_deg"] != a.peer["sun_zenith_deg"] ||
                b.peer["view_zenith_deg"] != a.peer["view_zenith_deg"])
                continue;
            std::printf("[ towards/away, sun %2.0f view %2.0f ]", a.peer["sun_zenith_deg"], a.peer["view_zenith_deg"]);
            for (int c = 0; c < 3; ++c) {
                const double p = (peer(a, "L_", c) - peer(a, "L1_", c)) / (peer(b, "L_", c) - peer(b, "L1_", c));
                const double e = a.ms_emulated[c] / b.ms_emulated[c], d = a.ms_ref[c] / b.ms_ref[c];
                std::printf("  %s peer %.3f lookup %.3f reference %.3f", kNames[c], p, e, d);
                EXPECT_LT(std::abs(e / p - 1.0), 0.05) << kNames[c];
            }
            std::printf("\n");
        }
    }
}

void reference_like_for_like() {
    std::vector<double> err[3][3];
    for (const Row& r : rows())
        for (int c = 0; c < 3; ++c) {
            const double L = peer(r, "L_", c);
            const double like = r.ss_trap50[c] + r.ms_emulated[c];
            err[sun_index(r)][c].push_back(like / L - 1.0);
            EXPECT_LT(std::abs(like / L - 1.0), sun_index(r) == 2 ? 0.025 : 0.02)
                << kNames[c] << " sun " << r.peer["sun_zenith_deg"] << " view " << r.peer["view_zenith_deg"]
                << " az " << r.peer["rel_azimuth_deg"];
        }
    for (int g = 0; g < 3; ++g)
        for (int c = 0; c < 3; ++c) {
            const auto [m, w] = abs_median_max(err[g][c]);
            std::printf("[ reference like for like, sun %2d, %s ] median %.2f %% worst %.2f %%\n", 30 * g, kNames[c],
                        100 * m, 100 * w);
        }
}

void lut_against_the_peer_corrected() {
    std::vector<double> err[3];
    for (const Row& r : rows())
        for (int c = 0; c < 3; ++c) {
            // The peer with its two measured errors taken out.
            const double corrected = peer(r, "L_", c) - (r.ss_trap50[c] - r.ss_exact[c]) -
                                     (r.ms_emulated[c] - r.ms_ref[c]);
            err[c].push_back(r.lut[c] / corrected - 1.0);
        }
    for (int c = 0; c < 3; ++c) {
        const auto [m, w] = abs_median_max(err[c]);
        std::printf("[ lut vs peer corrected, %s ] median %.2f %% worst %.2f %% (%zu views)\n", kNames[c], 100 * m,
                    100 * w, err[c].size());
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
// So the quadratures are a minor part of it; the texture lookup (above) is the cause.
// Runtime about 12 s on two loaded cores.
TEST(PeerMultipleScattering, PeerQuadraturesDoNotMakeTheAzimuthalStructure) {
    using welkin::test::SecondOrderRules;
    const Atmosphere atm = Atmosphere::preset("bruneton2017");
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
        det[std::size_t(k)] = second.radiance(atm.bottom_radius_m, v.z, s.z, glm::dot(v, s),
                                              k % 2 ? peer_rules : converged);
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
        for (int c = 0; c < 3; ++c) ref[i][std::size_t(c)] = double(two[std::size_t(c)]) - double(one[std::size_t(c)]);
    }
    for (int c = 0; c < 3; ++c) {
        for (std::size_t i = 0; i < 2; ++i) {
            const double conv = det[2 * i][std::size_t(c)], peer = det[2 * i + 1][std::size_t(c)];
            std::printf("[ second order, sun 30 view 60 az %3.0f, %s ] reference %.4e, converged quadrature %+.2f %%, "
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
        std::printf("[ second order towards/away, %s ] converged %.3f, peer's rules %.3f; the peer's orders 2-4 %.3f\n",
                    kNames[c], conv_ratio, peer_ratio, table_ratio);
        EXPECT_LT(std::abs(peer_ratio / conv_ratio - 1), 0.10) << kNames[c];
        EXPECT_GT(table_ratio / conv_ratio - 1, 0.25) << kNames[c];
    }
}
