// SPDX-License-Identifier: Apache-2.0
// The "analytic" method: single scattering in closed form, no marching per direction.
//
// 1. Columns by the Chapman function. For an exponential layer of scale height H, the
//    column (integral of density) from radius r along zenith angle chi to infinity is
//        N(r, chi) = H exp(-h / H) Ch(r / H, chi),
//    where Ch is Chapman's grazing-incidence function. We use the rational approximation
//        Ch(X, chi) ~ c / ((c - 1) cos(chi) + 1),   c = sqrt(pi X / 2),   chi <= 90 deg,
//    exact at chi = 0 and matching the asymptote Ch(X, 90 deg) = sqrt(pi X / 2) (Schuler
//    2012, "An Approximation to the Chapman Grazing-Incidence Function for Atmospheric
//    Scattering", GPU Pro 3). Beyond 90 degrees the ray passes its lowest point at radius
//    r sin(chi); the column there is the full chord minus the part behind the observer:
//        Ch(X, chi) = 2 Ch(X sin chi, 90) exp(X - X sin chi) - Ch(X, 180 deg - chi).
//    A segment from A to a ground point B is N(B, back towards A) - N(A, back towards B).
//    Layers that are not exponential (the ozone tent) are treated as a thin shell at their
//    mean altitude: vertical column divided by the cosine of the ray's zenith angle at that
//    altitude.
// 2. Single scattering with the sun's optical depth linear along the path. Let tau_v be
//    the view path's optical depth, tau_s0 the sun's optical depth at the observer and
//    tau_s1 at the path's end (0 where the ray leaves through the top). Assuming the sun's
//    optical depth varies linearly with the view path's optical depth x in [0, tau_v]
//    (exact for a plane-parallel atmosphere in which all constituents share one profile),
//        L = E sum_k sigma_s,k N_k P_k(nu) exp(-tau_s0) (1 - exp(-(tau_v + D))) / (tau_v + D),
//    with D = tau_s1 - tau_s0 and N_k the view path's column of constituent k.
//
// What it leaves out, on purpose (it is the bottom rung of the ladder, charted against the
// reference): multiple scattering (roughly 10-30 % of daytime sky radiance, more in the
// blue and at twilight), the variation of the mixture along the path, and the sun's
// illumination of the high atmosphere once the sun is below the observer's horizon
// (the sky goes dark when the observer's sun sets).
#include "welkin/sky/analytic.hpp"

#include <cmath>
#include <optional>

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/atmosphere/transmittance_lut.hpp"
#include "welkin/atmosphere/view_geometry.hpp"
#include "welkin/base/error.hpp"

namespace welkin {
namespace {

double chapman_up(double X, double cos_chi) {
    const double c = std::sqrt(kPi * X / 2.0);
    return c / ((c - 1.0) * cos_chi + 1.0);
}

// Ch(X, chi) for any chi; X = r / H.
double chapman(double X, double cos_chi) {
    if (cos_chi >= 0.0) return chapman_up(X, cos_chi);
    const double sin_chi = safe_sqrt(1.0 - cos_chi * cos_chi);
    // exp(X (1 - sin chi)) can overflow for long chords through dense air: cap the
    // exponent (the transmittance is 0 to double precision long before).
    const double e = std::min(X * (1.0 - sin_chi), 700.0);
    return 2.0 * chapman_up(X * sin_chi, 0.0) * std::exp(e) - chapman_up(X, -cos_chi);
}

// One constituent's column model: exponential (Chapman) or thin shell.
struct Column {
    std::optional<double> scale_height;
    double shell_radius = 0.0;    // thin shell: mean altitude's radius
    double vertical_total = 0.0;  // thin shell: ground-to-space vertical column
    double R = 0.0;

    // Column from radius r along zenith cosine mu to infinity (or 0 beyond the top for
    // rays that end there; the thin shell is crossed once for upward rays).
    double to_space(double r, double mu) const {
        if (scale_height) {
            const double H = *scale_height;
            return H * std::exp(-(r - R) / H) * chapman(r / H, mu);
        }
        if (vertical_total == 0.0) return 0.0;
        // Thin shell at shell_radius: crossed when the observer is below it (once, or
        // twice on a downward ray that misses the ground), else only downwards if the
        // ray comes down through it.
        const double disc = sphere_discriminant(r, mu, shell_radius);
        if (disc < 0.0) return 0.0;
        const double mu_shell = std::sqrt(disc) / shell_radius;  // |cos| at the crossing
        const double once = vertical_total / std::max(mu_shell, 1e-3);
        if (r <= shell_radius) return once;
        return mu < 0.0 ? 2.0 * once : 0.0;
    }
};

}  // namespace

AnalyticSky::AnalyticSky(const SkyOptions& options) : options_(options) { options_.validate(); }

void AnalyticSky::radiance(const Atmosphere& atm, const Observer& observer_in,
                           std::span<const glm::dvec3> directions_in, std::span<float> out,
                           std::span<float> standard_error, Progress* progress) const {
    const Observer observer =
        validate_deterministic_call(atm, observer_in, directions_in, out, standard_error);
    const std::span<const glm::dvec3> directions = directions_in;
    const std::size_t C = atm.channels();
    const double R = atm.bottom_radius_m, top = atm.top_radius_m;

    // Per-constituent column models, set up once per call (three vertical quadratures).
    auto make_column = [&](const DensityProfile& p) {
        Column col;
        col.R = R;
        col.scale_height = p.exponential_scale_height_m();
        if (!col.scale_height) {
            const double total = density_integral(p, R, R, 1.0, top - R);
            col.vertical_total = total;
            // Mean altitude, weighted by density (midpoint sums are plenty for a centroid).
            double moment = 0.0;
            const int n = 512;
            for (int i = 0; i < n; ++i) {
                const double h = (i + 0.5) / n * (top - R);
                moment += h * p.density(h) * (top - R) / n;
            }
            col.shell_radius = R + (total > 0.0 ? moment / total : 0.5 * (top - R));
        }
        return col;
    };
    const Column rayleigh = make_column(atm.rayleigh_density);
    const Column mie = make_column(atm.mie_density);
    const Column absorption = make_column(atm.absorption_density);
    // Columns N_k of a segment along (r, mu): to infinity, or to the ground point.
    struct Columns {
        double rayleigh, mie, absorption;
    };
    auto columns = [&](double r, double mu) -> Columns {
        if (!ray_hits_ground(r, mu, R))
            return {rayleigh.to_space(r, mu), mie.to_space(r, mu), absorption.to_space(r, mu)};
        const double d = distance_to_bottom(r, mu, R);
        const double mu_g = mu_at(r, mu, d, R);
        // Ground point B looking back up towards the observer, minus the observer looking on
        // past itself: both are upward-going columns.
        auto seg = [&](const Column& c) { return std::max(0.0, c.to_space(R, -mu_g) - c.to_space(r, -mu)); };
        return {seg(rayleigh), seg(mie), seg(absorption)};
    };
    auto tau = [&](std::size_t c, const Columns& n) {
        return atm.rayleigh_scattering[c] * n.rayleigh + atm.mie_extinction[c] * n.mie +
               atm.absorption_extinction[c] * n.absorption;
    };
    // Sun optical depth at a point, infinite (transmittance 0) once the planet hides it.
    auto sun_transmittance = [&](std::size_t c, double r, double mu_s) {
        const double fraction = sun_visible_fraction(R, r, mu_s, atm.sun_angular_radius_rad);
        if (fraction <= 0.0) return 0.0;
        const Columns n{rayleigh.to_space(r, mu_s), mie.to_space(r, mu_s), absorption.to_space(r, mu_s)};
        return std::exp(-tau(c, n)) * fraction;
    };

    double r = R + observer.altitude_m;
    ProgressTracker tracker(progress, directions.size());
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, directions.size(), 1024),
        [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                ViewGeometry g = view_geometry(directions[i], observer.sun_direction);
                double r0 = r;
                float* o = &out[i * C];
                if (r0 > top) {  // enter the atmosphere first
                    const double entry = distance_to_atmosphere_entry(r0, g.mu, top);
                    if (entry < 0.0) {
                        std::fill(o, o + C, 0.0f);
                        continue;
                    }
                    const double r_e = std::min(radius_at(r0, g.mu, entry), top);
                    g.mu_s = clamp_cosine((r0 * g.mu_s + entry * g.nu) / r_e);
                    g.mu = mu_at(r0, g.mu, entry, r_e);
                    r0 = r_e;
                }
                const Columns n = columns(r0, g.mu);
                const bool ground = ray_hits_ground(r0, g.mu, R);
                double mu_s_end = 0.0;
                if (ground) {
                    const double d = distance_to_bottom(r0, g.mu, R);
                    mu_s_end = clamp_cosine((r0 * g.mu_s + d * g.nu) / R);
                }
                const double p_r = rayleigh_phase(g.nu);
                const double p_m = mie_phase(atm.mie_phase, g.nu, atm.mie_g);
                for (std::size_t c = 0; c < C; ++c) {
                    const double T0 = sun_transmittance(c, r0, g.mu_s);
                    const double T1 = ground ? sun_transmittance(c, R, mu_s_end) : 1.0;
                    const double tau_v = tau(c, n);
                    double factor;  // integral over x of exp(-x) exp(-tau_s(x)) / tau_v
                    if (T0 <= 0.0 && T1 <= 0.0) {
                        factor = 0.0;
                    } else if (T0 <= 0.0 || T1 <= 0.0) {
                        // Half the path in the planet's shadow: light the lit half only, with the
                        // lit end's transmittance.
                        factor = 0.5 * std::max(T0, T1) * (1.0 - std::exp(-0.5 * tau_v)) /
                                 std::max(0.5 * tau_v, 1e-30);
                    } else {
                        const double D = -std::log(T1) + std::log(T0);  // tau_s1 - tau_s0
                        const double a = tau_v + D;
                        factor = T0 * (std::abs(a) > 1e-9 ? (1.0 - std::exp(-a)) / a : 1.0 - 0.5 * a);
                    }
                    const double scattered =
                        atm.rayleigh_scattering[c] * n.rayleigh * p_r + atm.mie_scattering[c] * n.mie * p_m;
                    const double L = atm.solar_irradiance[c] * scattered * factor;
                    o[c] = std::isfinite(L) ? float(std::max(L, 0.0)) : 0.0f;
                }
            }
            tracker.advance(range.size());
        });
    tracker.finish();
}

}  // namespace welkin
