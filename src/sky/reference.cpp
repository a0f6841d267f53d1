// SPDX-License-Identifier: Apache-2.0
// The reference sky: Monte-Carlo path tracing through a spherical atmosphere.
//
// What it computes. For an observer at x looking along v, the sky (path) radiance is the
// light scattered towards x by the air along the view ray, up to where the ray leaves
// the atmosphere or meets the ground (the ground's own radiance at the end of the ray is
// not part of it; sky/method.hpp):
//
//   L(x, v) = int_0^D T(x, y_t) sum_k sigma_k(y_t) int_S2 p_k(w . v) L_in(y_t, w) dw dt,   (1)
//
// k in {Rayleigh, Mie}, sigma_k the scattering coefficient, p_k the phase function
// (phase.hpp; nu = w . v where w points from y towards the light), T the transmittance,
// and L_in the radiance arriving at y from direction w. L_in is the sun, a point source
// of irradiance E in direction s, seen through T_sun and blocked by the planet (Earth
// shadow), plus diffuse light: the path radiance along w, and where w meets the ground,
// the Lambertian ground's radiance (albedo / pi times its irradiance, sun and sky)
// transmitted back to y. The sun's disc size is ignored for in-scattering (a point
// source: its 0.27 deg radius changes the phase function over the disc by < 1e-4 away
// from the forward peak, and the shadow boundary by the same angle), as in Bruneton 2017.
//
// Estimator. (1) splits into the light scattered once and the rest:
//
//   L = L1 + Lms,   L1 = int_0^D T(x, y_t) sum_k sigma_k(y_t) p_k(v . s) E T_sun(y_t) dt.
//
// * L1 by quadrature, no noise: [0, D] is cut at the ray's lowest point, at every
//   crossing of a density-profile breakpoint and at the boundaries of the Earth's
//   shadow (the ray against the cylinder of radius R behind the planet, along -s), so
//   the integrand is smooth on each piece; each piece gets 8-point Gauss-Legendre on 12
//   panels graded towards its low-altitude end (as optical_depth.cpp), where the air is
//   densest. tests/cpp/test_reference_sky.cpp checks it against a Richardson-extrapolated
//   fine trapezoid rule to 1e-4.
// * Lms by path tracing, unbiased.
//   - Event 1 is a point y on the view ray, drawn with a density proportional to the
//     channel average of each channel's normalised T(x, y) sigma(y), piecewise constant
//     on the quadrature panels (95 %), plus 5 % uniform over [0, D] so that no part of
//     the ray has zero density.
//   - At every scattering event the next direction comes from the phase functions: a
//     Rayleigh/Mie mixture with the channel-averaged local Rayleigh share as the
//     Rayleigh probability, Cornette-Shanks drawn through Henyey-Greenstein with the
//     same g (their ratio stays within [0.56, 1.14] for g = 0.8); the throughput takes
//     sum_k sigma_k,c p_k(nu) / pdf(w).
//   - Every flight, from the current point along w to the ground or the top (length D),
//     adds the sun scattered at its end by next-event estimation in both places it can
//     happen: (a) in the air, at a forced collision s drawn from the free-flight density
//     conditioned on colliding before D and outside the Earth's shadow (where the
//     integrand vanishes; the shadow is one interval [a, b] of the flight, the line
//     against the shadow cylinder cut by the terminator plane), sigma_t(s) T(s) / M with
//     M = 1 - T(a) + T(b) - T(D), weighted with sigma_s p(w . s) E T_sun(s) (T_sun from
//     the column table); (b) at the ground, if the ray meets it, with its exact weight
//     T(D) albedo / pi E T_sun cos. Every path thus scores on every flight (plain
//     free-flight sampling leaves ~40 % of the paths escaping with nothing), and in
//     twilight the samples land where the sun is.
//   - The path then continues with a collision with probability 1 - T(D) (at the same s
//     when the flight has no shadow, whose distribution is then the right one; else at a
//     new distance), else from the ground (cosine-weighted direction, weight albedo) or
//     it ends in space: together this is regular tracking, density sigma_t(s) T(s) per
//     collision and T(D) for reaching the end. Distances solve tau(s) = tau* by
//     safeguarded Newton on the column table (d tau / ds is the local extinction).
//   - Channels: one path carries all of them (three, or the 48 of the spectral mode, at
//     about the same cost). Distances are sampled with one "hero" channel per path
//     (cycling through the channels over a batch from a random offset), and each
//     channel c is weighted by its path integrand over the channel average of the path
//     densities (one-sample MIS with the balance heuristic over whole paths; Wilkie et
//     al. 2014, "Hero wavelength spectral sampling", EGSR; Veach 1997 ch. 9). No
//     channel's weight exceeds C times the weight its own sampling would give it.
//     (Directions and the view-ray point are sampled the same way for every channel.)
//   - Russian roulette (Arvo & Kirk 1990) from the second event on: survival
//     q = min(1, max_c beta_c / beta1_c), beta1 the throughput after event 1, and
//     q *= 0.9 beyond 64 events; survivors are divided by q, so it stays unbiased.
//     A hard stop at 100000 events (never reached in practice) keeps pathological
//     inputs from hanging.
//   - The point sun is reached only by next-event estimation and a sampled direction
//     never hits it, so no light is counted twice. Scattering orders: the view-ray point
//     is event 1, the sun added on the flight after event m is order m + 1; ground
//     reflections count as events. max_scattering_order = n keeps orders <= n.
//   - Sampling decisions come from randomised quasi-Monte Carlo points (QmcSampler in
//     base/rng.hpp: padded, Owen-scrambled Sobol' pairs, exactly uniform per
//     point): event 1 uses (view-ray point, lobe), (cosine, azimuth); each flight
//     (forced collision, continue?) and each later event (lobe, -), (cosine, azimuth),
//     so the pairs stay aligned with the events; beyond 24 dimensions, and for the
//     roulette, plain pseudo-random numbers.
//
// Transmittances come from ColumnTable (atmosphere/column_table.hpp): exact closed forms
// for piecewise-linear layers (ozone) and a fine double-precision table of the exact
// columns for the exponential ones, checked against optical_depth.hpp to 1e-5 in
// tests/cpp/test_optical_depth.cpp; nothing is shared with the LUT methods. The free-
// flight density uses the table's optical depth for the sampling and the exact local
// extinction for its derivative; they agree to the table's accuracy, so the weights are
// unbiased to ~1e-5 of the multiple-scattering part.
//
// Standard error. The paths of a direction are split into kBatches batches of
// consecutive path indices; each batch is an independent randomised-QMC replicate (its
// own scrambling seeds) and its mean an unbiased estimate of Lms, so the standard error
// is sd(batch means) / sqrt(kBatches) (L1 adds none; with 32 batches the estimate of the
// error is itself good to ~13 %). With fewer paths than batches each path is its own
// batch; with one path the error cannot be estimated and the estimate itself is reported
// as its error.
//
// Determinism. Random numbers come from PathRng keyed by (seed, direction, path) and the
// batch's scrambling seeds from (seed, direction, batch); work is split over (direction,
// batch) and summed in a fixed order, so the output is identical for any thread count.
#include "welkin/sky/reference.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "welkin/atmosphere/column_table.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/phase.hpp"
#include "welkin/atmosphere/phase_sampling.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/quadrature.hpp"
#include "welkin/base/rng.hpp"

namespace welkin {
namespace {

// Panels per smooth piece of the view ray, growing geometrically away from its low end.
constexpr int kPanels = 12;
constexpr double kPanelGrowth = 1.6;
// Share of the view-ray sampling density spread uniformly (defensive mixture).
constexpr double kUniformShare = 0.05;
constexpr int kRouletteDepth = 64;
constexpr int kMaxEvents = 100000;

// The atmosphere's coefficients, per channel, in flat arrays.
struct Medium {
    std::size_t C;
    const Atmosphere* atm;
    const ColumnTable* table;
    std::vector<double> rayleigh, mie_scattering, mie_extinction, absorption, sun, albedo;
    MiePhaseModel mie_phase;
    double g, R, top;
    glm::dvec3 s;  // towards the sun

    struct Densities {
        double rayleigh, mie, absorption;
    };
    Densities densities(double r) const {
        const double h = r - R;
        return {atm->rayleigh_density.density(h), atm->mie_density.density(h),
                atm->absorption_density.density(h)};
    }
    double tau(std::size_t c, const ColumnDensity& col) const {
        return rayleigh[c] * col.rayleigh_m + mie_extinction[c] * col.mie_m +
               absorption[c] * col.absorption_m;
    }
    double extinction(std::size_t c, const Densities& d) const {
        return rayleigh[c] * d.rayleigh + mie_extinction[c] * d.mie + absorption[c] * d.absorption;
    }
    // The part [a, b] of [0, length] of the ray p + t w that lies in the Earth's shadow,
    // {y : y . s < 0 and |y - (y . s) s| < R} (a cylinder behind the planet cut by the
    // terminator plane: convex, so a line meets it in one interval). None: a = b = length.
    void shadow_interval(const glm::dvec3& p, const glm::dvec3& w, double length, double& a,
                         double& b) const {
        a = b = length;
        double lo = -1e300, hi = 1e300;
        const glm::dvec3 pa = p - glm::dot(p, s) * s, wb = w - glm::dot(w, s) * s;
        const double bb = glm::dot(wb, wb), ab = glm::dot(pa, wb), aa = glm::dot(pa, pa) - R * R;
        if (bb > 1e-300) {
            const double disc = ab * ab - bb * aa;
            if (!(disc > 0.0)) return;
            const double root = std::sqrt(disc);
            lo = (-ab - root) / bb;
            hi = (-ab + root) / bb;
        } else if (!(aa < 0.0)) {
            return;
        }
        const double ps = glm::dot(p, s), ws = glm::dot(w, s);
        if (ws > 0.0)
            hi = std::min(hi, -ps / ws);
        else if (ws < 0.0)
            lo = std::max(lo, -ps / ws);
        else if (!(ps < 0.0))
            return;
        lo = std::max(lo, 0.0);
        hi = std::min(hi, length);
        if (hi > lo) {
            a = lo;
            b = hi;
        }
    }

    // Transmittance towards the sun from position p (radius r), 0 in the Earth's shadow.
    void sun_transmittance(const glm::dvec3& p, double r, double* out) const {
        const double mu_s = clamp_cosine(glm::dot(p, s) / r);
        if (ray_hits_ground(r, mu_s, R)) {
            std::fill(out, out + C, 0.0);
            return;
        }
        const ColumnDensity col = table->to_top(r, mu_s);
        for (std::size_t c = 0; c < C; ++c) out[c] = std::exp(-tau(c, col));
    }
};

// One panel of the view ray: [a, a + width), its share of the path-start density.
struct Panel {
    double a, width, probability;
};

// What one direction needs: L1 and the distribution of path starts.
struct ViewRay {
    bool inside = false;  // false: misses the atmosphere, radiance 0
    glm::dvec3 start{0.0};
    double r = 0, mu = 0, length = 0;
    std::vector<double> single;  // L1 per channel
    std::vector<Panel> panels;
    std::vector<double> cdf;   // cumulative panel probabilities, cdf.back() == 1
    bool scatters = false;     // some channel scatters somewhere along the ray
    ColumnTable::Ray columns;  // of the view ray, from `start`
};

// The cuts of [0, length] described in the derivation.
std::vector<double> view_ray_cuts(const Medium& m, const glm::dvec3& p, const glm::dvec3& v, double r,
                                  double mu, double length) {
    std::vector<double> cuts{0.0, length};
    auto add = [&](double t) {
        if (t > 0.0 && t < length) cuts.push_back(t);
    };
    add(-r * mu);
    for (const DensityProfile* prof :
         {&m.atm->rayleigh_density, &m.atm->mie_density, &m.atm->absorption_density})
        for (double hb : prof->breakpoints_m()) {
            const double disc = sphere_discriminant(r, mu, m.R + hb);
            if (disc < 0.0) continue;
            add(-r * mu - std::sqrt(disc));
            add(-r * mu + std::sqrt(disc));
        }
    // Earth's shadow: |a + t b| = R with a, b the components of p, v across s.
    const glm::dvec3 a = p - glm::dot(p, m.s) * m.s, b = v - glm::dot(v, m.s) * m.s;
    const double bb = glm::dot(b, b), ab = glm::dot(a, b), aa = glm::dot(a, a);
    if (bb > 1e-300) {
        const double disc = ab * ab - bb * (aa - m.R * m.R);
        if (disc > 0.0) {
            add((-ab - std::sqrt(disc)) / bb);
            add((-ab + std::sqrt(disc)) / bb);
        }
    }
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    return cuts;
}

ViewRay prepare_view_ray(const Medium& m, const glm::dvec3& x, const glm::dvec3& v) {
    ViewRay vr;
    vr.single.assign(m.C, 0.0);
    double r = glm::length(x);
    const double mu0 = clamp_cosine(glm::dot(x, v) / r);
    glm::dvec3 p = x;
    if (r > m.top) {
        const double entry = distance_to_atmosphere_entry(r, mu0, m.top);
        if (entry < 0.0) return vr;
        p = x + entry * v;
    }
    r = std::clamp(glm::length(p), m.R, m.top);
    const double mu = clamp_cosine(glm::dot(p, v) / glm::length(p));
    const ColumnTable::Ray ray = m.table->ray(r, mu);
    if (!(ray.length() > 0.0)) return vr;
    vr.inside = true;
    vr.start = p;
    vr.r = r;
    vr.mu = mu;
    vr.length = ray.length();
    vr.columns = ray;

    const double nu = clamp_cosine(glm::dot(v, m.s));
    const double p_r = rayleigh_phase(nu), p_m = mie_phase(m.mie_phase, nu, m.g);
    const std::vector<double> cuts = view_ray_cuts(m, p, v, r, mu, vr.length);
    std::vector<double> t_view(m.C), t_sun(m.C), weight_sum(m.C, 0.0);
    std::vector<std::vector<double>> panel_weight;  // [panel][channel]
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
        const double a = cuts[i], b = cuts[i + 1];
        if (!(b > a)) continue;
        const bool low_at_a = radius_at(r, mu, a) <= radius_at(r, mu, b);
        // Panel k has width w0 growth^k from the low end; their widths sum to b - a.
        const double w0 = (b - a) * (kPanelGrowth - 1.0) / (std::pow(kPanelGrowth, kPanels) - 1.0);
        double pos = 0.0, w = w0;
        for (int k = 0; k < kPanels; ++k) {
            const double lo = pos, hi = (k + 1 == kPanels) ? (b - a) : pos + w;
            pos = hi;
            w *= kPanelGrowth;
            const double pa = low_at_a ? a + lo : b - hi, pb = low_at_a ? a + hi : b - lo;
            if (!(pb > pa)) continue;
            std::vector<double> pw(m.C, 0.0);
            const double mid = 0.5 * (pa + pb), half = 0.5 * (pb - pa);
            for (int n = 0; n < 8; ++n) {
                const double t = mid + (n < 4 ? -1.0 : 1.0) * half * kGauss8Nodes[std::size_t(n % 4)];
                const double wq = half * kGauss8Weights[std::size_t(n % 4)];
                const glm::dvec3 y = p + t * v;
                const double ry = glm::length(y);
                const Medium::Densities d = m.densities(ry);
                const ColumnDensity col = ray.upto(t);
                m.sun_transmittance(y, ry, t_sun.data());
                for (std::size_t c = 0; c < m.C; ++c) {
                    t_view[c] = std::exp(-m.tau(c, col));
                    const double s_r = m.rayleigh[c] * d.rayleigh, s_m = m.mie_scattering[c] * d.mie;
                    vr.single[c] += wq * t_view[c] * (s_r * p_r + s_m * p_m) * m.sun[c] * t_sun[c];
                    pw[c] += wq * t_view[c] * (s_r + s_m);
                }
            }
            for (std::size_t c = 0; c < m.C; ++c) weight_sum[c] += pw[c];
            vr.panels.push_back({pa, pb - pa, 0.0});
            panel_weight.push_back(std::move(pw));
        }
    }
    // Path-start distribution: the channel average of each channel's normalised
    // T sigma_s, plus the uniform share.
    std::size_t active = 0;
    for (std::size_t c = 0; c < m.C; ++c) active += weight_sum[c] > 0.0 ? 1 : 0;
    vr.scatters = active > 0 && !vr.panels.empty();
    double total = 0.0;
    for (std::size_t i = 0; i < vr.panels.size(); ++i) {
        double share = 0.0;
        for (std::size_t c = 0; c < m.C; ++c)
            if (weight_sum[c] > 0.0) share += panel_weight[i][c] / weight_sum[c];
        share = active > 0 ? share / double(active) : 0.0;
        vr.panels[i].probability =
            (1.0 - kUniformShare) * share + kUniformShare * vr.panels[i].width / vr.length;
        total += vr.panels[i].probability;
    }
    double acc = 0.0;
    for (Panel& pn : vr.panels) {
        pn.probability /= total;
        acc += pn.probability;
        vr.cdf.push_back(acc);
    }
    if (!vr.cdf.empty()) vr.cdf.back() = 1.0;
    return vr;
}

// Traces the paths of one batch of one direction; adds each path's Lms to `sum`.
class PathTracer {
public:
    PathTracer(const Medium& m, int max_order)
        : m_(m),
          max_order_(max_order),
          beta_(m.C),
          beta1_(m.C),
          q_(m.C),
          p_seg_(m.C),
          tau_(m.C),
          tr_(m.C),
          tr_end_(m.C),
          lit_(m.C),
          sun_t_(m.C),
          contrib_(m.C) {}

    // `qmc` supplies the sampling decisions, four dimensions per event (see the
    // derivation), `rng` the roulette; `hero` is the channel whose free-flight
    // distribution samples the distances.
    void trace(const ViewRay& vr, const glm::dvec3& v, PathRng& rng, QmcSampler& qmc, std::size_t hero,
               std::vector<double>& sum) {
        std::fill(contrib_.begin(), contrib_.end(), 0.0);
        trace_path(vr, v, rng, qmc, hero);
        for (std::size_t c = 0; c < m_.C; ++c) sum[c] += contrib_[c];
    }

private:
    // Mixture probability of the Rayleigh lobe at a point, and the per-channel phase
    // factor f_c(nu) = sum_k sigma_k,c p_k(nu).
    double rayleigh_share(const Medium::Densities& d) const {
        double share = 0.0;
        std::size_t n = 0;
        for (std::size_t c = 0; c < m_.C; ++c) {
            const double s_r = m_.rayleigh[c] * d.rayleigh, s_m = m_.mie_scattering[c] * d.mie;
            if (s_r + s_m > 0.0) {
                share += s_r / (s_r + s_m);
                ++n;
            }
        }
        return n > 0 ? share / double(n) : 0.5;
    }

    // Samples a new direction at a scattering point and multiplies beta by f / pdf.
    // Consumes three sampler dimensions (lobe, cosine, azimuth), or four with `pad`.
    glm::dvec3 scatter(const glm::dvec3& w, const Medium::Densities& d, QmcSampler& qmc, bool pad = true) {
        const double p_share = rayleigh_share(d);
        const double u_lobe = qmc.next();
        if (pad) qmc.skip(1);
        const double u_cos = qmc.next(), u_phi = qmc.next();
        const double cos_theta =
            u_lobe < p_share ? sample_rayleigh_cosine(u_cos) : sample_henyey_greenstein_cosine(u_cos, m_.g);
        const glm::dvec3 w_new = direction_about(w, cos_theta, u_phi);
        const double nu = clamp_cosine(glm::dot(w, w_new));
        const double p_r = rayleigh_phase(nu), p_m = mie_phase(m_.mie_phase, nu, m_.g);
        const double pdf = p_share * p_r + (1.0 - p_share) * henyey_greenstein_phase(nu, m_.g);
        for (std::size_t c = 0; c < m_.C; ++c)
            beta_[c] *= (m_.rayleigh[c] * d.rayleigh * p_r + m_.mie_scattering[c] * d.mie * p_m) / pdf;
        return w_new;
    }

    // Sun by next-event estimation at a scattering point z (radius r) reached along w.
    // Sun by next-event estimation at a scattering point z (radius r) reached along w;
    // `weight` multiplies beta (the flight's f / pdf less the transmittance, in tr_).
    void sun_at_scattering(const glm::dvec3& z, double r, const glm::dvec3& w, const Medium::Densities& d,
                           double weight) {
        m_.sun_transmittance(z, r, sun_t_.data());
        const double nu = clamp_cosine(glm::dot(w, m_.s));
        const double p_r = rayleigh_phase(nu), p_m = mie_phase(m_.mie_phase, nu, m_.g);
        for (std::size_t c = 0; c < m_.C; ++c)
            contrib_[c] += beta_[c] * weight * tr_[c] *
                           (m_.rayleigh[c] * d.rayleigh * p_r + m_.mie_scattering[c] * d.mie * p_m) *
                           m_.sun[c] * sun_t_[c];
    }

    // The distance s in (0, ray.length()) at which channel j's optical depth along the ray
    // reaches tau_target (which must be below its total); sets tau_ to every channel's
    // optical depth over [0, s]. Safeguarded Newton on g(s) = tau_j(s) - tau*, whose
    // derivative is the local extinction of channel j; g(0) < 0 < g(length).
    double solve_distance(const ColumnTable::Ray& ray, const glm::dvec3& pos, const glm::dvec3& w,
                          std::size_t j, double tau_target) {
        const double length = ray.length();
        double lo = 0.0, hi = length;
        const double ext0 = m_.extinction(j, m_.densities(glm::length(pos)));
        double s = ext0 > 0.0 ? tau_target / ext0 : 0.5 * length;
        if (!(s > lo && s < hi)) s = 0.5 * (lo + hi);
        ColumnDensity col{};
        for (int it = 0; it < 100; ++it) {
            col = ray.upto(s);
            const double g = m_.tau(j, col) - tau_target;
            if (std::abs(g) <= 1e-12 * (1.0 + tau_target) || hi - lo <= 1e-9 * length) break;
            if (g < 0.0)
                lo = s;
            else
                hi = s;
            const double ext = m_.extinction(j, m_.densities(glm::length(pos + s * w)));
            double next = ext > 0.0 ? s - g / ext : 0.5 * (lo + hi);
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
            s = next;
        }
        for (std::size_t c = 0; c < m_.C; ++c) tau_[c] = m_.tau(c, col);
        return s;
    }

    // Russian roulette before event `event`: false ends the path; a survivor's throughput
    // is divided by its survival probability.
    bool survives_roulette(int event, PathRng& rng) {
        double q = 0.0;
        for (std::size_t c = 0; c < m_.C; ++c)
            if (beta1_[c] > 0.0) q = std::max(q, beta_[c] / beta1_[c]);
        q = std::min(1.0, q);
        if (event > kRouletteDepth) q *= 0.9;
        if (q < 1.0) {
            if (!(rng.uniform() < q)) return false;
            for (double& b : beta_) b /= q;
        }
        return true;
    }

    // lit_[c]: the probability mass of channel c's free flight from pos along w (the whole
    // ray's column col_end) outside the Earth's shadow [a, b], 1 - T(a) + T(b) - T(D); and
    // for the hero, before_h = 1 - T_h(a), after_h = T_h(b). True when the ray crosses the
    // shadow (else lit_ is 1 - T(D) and the two stay as they are).
    bool lit_fractions(const ColumnTable::Ray& ray, const glm::dvec3& pos, const glm::dvec3& w,
                       const ColumnDensity& col_end, std::size_t hero, double& before_h, double& after_h) {
        double shadow_a, shadow_b;
        m_.shadow_interval(pos, w, ray.length(), shadow_a, shadow_b);
        if (!(shadow_a < ray.length())) {
            for (std::size_t c = 0; c < m_.C; ++c) lit_[c] = -std::expm1(-m_.tau(c, col_end));
            return false;
        }
        const ColumnDensity ca = ray.upto(shadow_a), cb = ray.upto(shadow_b);
        for (std::size_t c = 0; c < m_.C; ++c)
            lit_[c] = -std::expm1(-m_.tau(c, ca)) + (std::exp(-m_.tau(c, cb)) - tr_end_[c]);
        before_h = -std::expm1(-m_.tau(hero, ca));
        after_h = std::exp(-m_.tau(hero, cb));
        return true;
    }

    // The sun reflected by the Lambertian ground where the flight from pos along w ends
    // (the ray meets the ground), with its exact weight T_c(D), added to contrib_; returns
    // the ground's unit normal there.
    glm::dvec3 sun_at_ground(const ColumnTable::Ray& ray, const glm::dvec3& pos, const glm::dvec3& w) {
        const glm::dvec3 ground = glm::normalize(pos + ray.length() * w);
        const double cos_sun = glm::dot(ground, m_.s);
        if (cos_sun > 0.0) {
            m_.sun_transmittance(ground * m_.R, m_.R, sun_t_.data());
            for (std::size_t c = 0; c < m_.C; ++c)
                contrib_[c] += beta_[c] * tr_end_[c] * m_.albedo[c] / kPi * m_.sun[c] * sun_t_[c] * cos_sun;
        }
        return ground;
    }

    void trace_path(const ViewRay& vr, const glm::dvec3& v, PathRng& rng, QmcSampler& qmc, std::size_t hero) {
        const double u_start = qmc.next();
        // Event 1: a point on the view ray, from the panel distribution.
        const std::size_t i =
            std::size_t(std::lower_bound(vr.cdf.begin(), vr.cdf.end(), u_start) - vr.cdf.begin());
        const std::size_t pi = std::min(i, vr.panels.size() - 1);
        const Panel& panel = vr.panels[pi];
        const double below = pi > 0 ? vr.cdf[pi - 1] : 0.0;
        const double frac = std::clamp((u_start - below) / panel.probability, 0.0, 1.0);
        const double t = panel.a + frac * panel.width;
        const double pdf_t = panel.probability / panel.width;
        const ColumnDensity col = vr.columns.upto(t);
        glm::dvec3 pos = vr.start + t * v;
        double r = glm::length(pos);
        Medium::Densities d = m_.densities(r);
        for (std::size_t c = 0; c < m_.C; ++c) beta_[c] = std::exp(-m_.tau(c, col)) / pdf_t;
        std::fill(q_.begin(), q_.end(), 1.0);
        glm::dvec3 w = scatter(v, d, qmc, false);
        beta1_ = beta_;

        for (int event = 2; event <= kMaxEvents; ++event) {
            if (!survives_roulette(event, rng)) return;
            // The flight from pos along w, of length D to the ground or the top.
            r = std::clamp(glm::length(pos), m_.R, m_.top);
            const ColumnTable::Ray ray = m_.table->ray(r, clamp_cosine(glm::dot(pos, w) / r));
            const ColumnDensity col_end = ray.upto(ray.length());
            for (std::size_t c = 0; c < m_.C; ++c) tr_end_[c] = std::exp(-m_.tau(c, col_end));
            const double u_flight = qmc.next(), u_collide = qmc.next();
            const double collide_h = -std::expm1(-m_.tau(hero, col_end));  // 1 - T_h(D)

            // The sun scattered at event `event` on this flight, both branches at once:
            // (a) in the air, at a forced collision s drawn from the hero's free-flight
            // density restricted to the part of the flight outside the Earth's shadow
            // [a, b] (where the integrand vanishes), p_j(s) = sigma_t,j T_j(s) / M_j with
            // M_j = 1 - T_j(a) + T_j(b) - T_j(D): in daylight the shadow is empty and this
            // is the free-flight density conditioned on colliding; in twilight it keeps the
            // samples where the sun is; (b) at the ground, if the ray meets it, with its
            // exact weight T_c(D).
            double before_h = 0.0, after_h = 0.0;  // 1 - T_h(a), T_h(b)
            const bool shadowed = lit_fractions(ray, pos, w, col_end, hero, before_h, after_h);
            double s = 0.0;
            glm::dvec3 z{0.0};
            if (lit_[hero] > 0.0) {
                const double before = shadowed ? before_h : lit_[hero];
                const double mass = u_flight * lit_[hero];
                const double tau_target = mass < before
                                              ? -std::log1p(-mass)
                                              // past the shadow: T(tau*) = T_h(b) - (mass - before)
                                              : -std::log(std::max(after_h - (mass - before), 1e-300));
                s = solve_distance(ray, pos, w, hero, tau_target);
                z = pos + s * w;
                r_z_ = std::clamp(glm::length(z), m_.R, m_.top);
                d = m_.densities(r_z_);
                double mean = 0.0;
                for (std::size_t c = 0; c < m_.C; ++c) {
                    tr_[c] = std::exp(-tau_[c]);
                    p_seg_[c] = m_.extinction(c, d) * tr_[c];  // regular-tracking density
                    mean += lit_[c] > 0.0 ? q_[c] * p_seg_[c] / lit_[c] : 0.0;
                }
                mean /= double(m_.C);
                if (mean > 0.0) sun_at_scattering(z, r_z_, w, d, 1.0 / mean);
            }
            const glm::dvec3 ground = ray.hits_ground() ? sun_at_ground(ray, pos, w) : glm::dvec3(0.0);
            if (max_order_ > 0 && event >= max_order_) return;

            // Continue: collide with probability 1 - T_h(D), which makes the continuation
            // regular tracking: density sigma_t,j T_j(s) for channel j, or T_j(D) for
            // reaching the end of the ray. Without shadow the collision is the same s (its
            // distribution is the conditional one); with shadow, a new distance.
            if (u_collide < collide_h) {
                if (shadowed || !(lit_[hero] > 0.0)) {
                    s = solve_distance(ray, pos, w, hero, -std::log1p(-u_collide));
                    z = pos + s * w;
                    r_z_ = std::clamp(glm::length(z), m_.R, m_.top);
                    d = m_.densities(r_z_);
                    for (std::size_t c = 0; c < m_.C; ++c) {
                        tr_[c] = std::exp(-tau_[c]);
                        p_seg_[c] = m_.extinction(c, d) * tr_[c];
                    }
                }
                if (!(p_seg_[hero] > 0.0)) return;
                mis_update(tr_, p_seg_);
                pos = z;
                w = scatter(w, d, qmc);
                continue;
            }
            if (!ray.hits_ground() || !(tr_end_[hero] > 0.0)) return;
            mis_update(tr_end_, tr_end_);
            bool any = false;
            for (std::size_t c = 0; c < m_.C; ++c) {
                beta_[c] *= m_.albedo[c];
                any = any || beta_[c] > 0.0;
            }
            if (!any) return;
            pos = ground * m_.R;
            qmc.skip(2);
            const double u1 = qmc.next(), u2 = qmc.next();
            w = sample_cosine_hemisphere(ground, u1, u2);
        }
    }

    const Medium& m_;
    int max_order_;
    // Hero-wavelength MIS over whole paths (see the derivation): beta_c is channel c's
    // path throughput divided by the channel-averaged path density, and q_j the path
    // density under channel j's distance sampling over that average (mean of q_ is 1).
    // A free flight whose density is p_j under channel j and whose integrand factor is
    // f_c updates beta_c *= f_c / mean_j(q_j p_j) and q_j *= p_j / mean_k(q_k p_k).
    void mis_update(const std::vector<double>& f, const std::vector<double>& p) {
        double mean = 0.0;
        for (std::size_t j = 0; j < m_.C; ++j) mean += q_[j] * p[j];
        mean /= double(m_.C);
        for (std::size_t c = 0; c < m_.C; ++c) {
            beta_[c] *= f[c] / mean;
            q_[c] *= p[c] / mean;
        }
    }

    std::vector<double> beta_, beta1_, q_, p_seg_, tau_, tr_, tr_end_, lit_, sun_t_, contrib_;
    double r_z_ = 0.0;
};

}  // namespace

ReferenceSky::ReferenceSky(const SkyOptions& options, int max_scattering_order)
    : options_(options), max_order_(max_scattering_order) {
    options_.validate();
    require_in_range("max_scattering_order", max_scattering_order, 0, 1000000);
}

void ReferenceSky::radiance(const Atmosphere& atmosphere, const Observer& observer,
                            std::span<const glm::dvec3> directions, std::span<float> out,
                            std::span<float> standard_error, Progress* progress) const {
    atmosphere.validate();
    options_.validate();
    const Observer obs = observer.validated();
    validate_directions(directions);
    std::vector<glm::dvec3> dirs(directions.begin(), directions.end());
    for (glm::dvec3& d : dirs) d /= std::sqrt(glm::dot(d, d));
    const std::size_t C = atmosphere.channels(), N = dirs.size();
    if (out.size() != N * C)
        throw InvalidArgument("out", fmt::format("must hold directions x channels = {} floats, "
                                                 "got {}",
                                                 N * C, out.size()));
    if (!standard_error.empty() && standard_error.size() != N * C)
        throw InvalidArgument("standard_error", fmt::format("must be empty or hold {} floats, got {}", N * C,
                                                            standard_error.size()));

    const std::shared_ptr<const ColumnTable> table = ColumnTable::shared(atmosphere);
    Medium m;
    m.C = C;
    m.atm = &atmosphere;
    m.table = table.get();
    m.rayleigh = atmosphere.rayleigh_scattering;
    m.mie_scattering = atmosphere.mie_scattering;
    m.mie_extinction = atmosphere.mie_extinction;
    m.absorption = atmosphere.absorption_extinction;
    m.sun = atmosphere.solar_irradiance;
    m.albedo = atmosphere.ground_albedo;
    m.mie_phase = atmosphere.mie_phase;
    m.g = atmosphere.mie_g;
    m.R = atmosphere.bottom_radius_m;
    m.top = atmosphere.top_radius_m;
    m.s = obs.sun_direction;
    const glm::dvec3 x(0.0, 0.0, atmosphere.bottom_radius_m + obs.altitude_m);

    const std::size_t paths = std::size_t(options_.reference_paths);
    const std::size_t batches = std::min<std::size_t>(kBatches, paths);
    const bool multiple = max_order_ != 1;
    ProgressTracker tracker(progress, N + (multiple ? N * batches : 0));

    std::vector<ViewRay> rays(N);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            rays[i] = prepare_view_ray(m, x, dirs[i]);
            tracker.advance();
        }
    });

    // Batch sums of Lms, [direction][batch][channel].
    std::vector<double> sums(multiple ? N * batches * C : 0, 0.0);
    if (multiple)
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, N * batches, 1), [&](const auto& range) {
            PathTracer tracer(m, max_order_);
            std::vector<double> sum(C);
            for (std::size_t item = range.begin(); item != range.end(); ++item) {
                const std::size_t i = item / batches, b = item % batches;
                const ViewRay& vr = rays[i];
                if (vr.inside && vr.scatters) {
                    std::fill(sum.begin(), sum.end(), 0.0);
                    const std::size_t first = b * paths / batches;
                    const std::size_t last = (b + 1) * paths / batches;
                    // Heroes cycle through the channels from a random offset, so each
                    // path's hero is uniform and a batch balances them.
                    PathRng batch_rng(options_.seed, i, b, 1);
                    const std::size_t offset = std::size_t(batch_rng.next_u64() % C);
                    const std::uint64_t batch_key = batch_rng.next_u64();
                    for (std::size_t k = first; k < last; ++k) {
                        PathRng rng(options_.seed, i, k);
                        QmcSampler qmc(batch_key, std::uint32_t(k - first), rng);
                        tracer.trace(vr, dirs[i], rng, qmc, (k - first + offset) % C, sum);
                    }
                    std::copy(sum.begin(), sum.end(), sums.begin() + std::ptrdiff_t(item * C));
                }
                tracker.advance();
            }
        });
    tracker.finish();

    for (std::size_t i = 0; i < N; ++i)
        for (std::size_t c = 0; c < C; ++c) {
            double total = 0.0, se = 0.0;
            if (rays[i].inside) {
                total = rays[i].single[c];
                if (multiple) {
                    double ms = 0.0, mean_of_means = 0.0;
                    std::vector<double> means(batches);
                    for (std::size_t b = 0; b < batches; ++b) {
                        const double s = sums[(i * batches + b) * C + c];
                        const double n = double((b + 1) * paths / batches - b * paths / batches);
                        ms += s;
                        means[b] = s / n;
                        mean_of_means += means[b];
                    }
                    ms /= double(paths);
                    mean_of_means /= double(batches);
                    if (batches > 1) {
                        double var = 0.0;
                        for (double mb : means) var += (mb - mean_of_means) * (mb - mean_of_means);
                        se = std::sqrt(var / double(batches - 1) / double(batches));
                    } else {
                        se = std::abs(ms);
                    }
                    total += ms;
                }
            }
            out[i * C + c] = float(total);
            if (!standard_error.empty()) standard_error[i * C + c] = float(se);
        }
}

}  // namespace welkin
