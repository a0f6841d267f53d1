// SPDX-License-Identifier: Apache-2.0
// Apparent topocentric sun and moon (include/welkin/astro/positions.hpp has the method and
// its sources).
#include "welkin/astro/positions.hpp"

#include <algorithm>
#include <cmath>

#include <erfa.h>
#include <erfam.h>

#include "welkin/astro/moonlight.hpp"
#include "welkin/base/error.hpp"

namespace welkin {
namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec add(const Vec& a, const Vec& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec scale(const Vec& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }
Vec unit(const Vec& a) { return scale(a, 1.0 / norm(a)); }

// r p for a 3x3 rotation (ERFA's functions take non-const arrays: copy).
Vec mul(const double (&r)[3][3], const Vec& p) {
    double m[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m[i][j] = r[i][j];
    Vec out{};
    Vec in = p;
    eraRxp(m, in.data(), out.data());
    return out;
}

// Speed of light in au per day.
constexpr double kC_au_day = ERFA_DAYSEC / ERFA_AULT;

// Earth / Moon mass ratio (JPL DE421, Folkner et al. 2008, IOM 343R-08-003).
constexpr double kEarthMoonMassRatio = 81.30056907;

// The frames of one moment and place: what every body's position goes through.
struct Frames {
    double rbpn[3][3];                  // GCRS -> true equator and equinox of date
    double rc2t[3][3];                  // GCRS -> ITRS (polar motion neglected)
    Vec observer_gcrs_au{};             // observer's geocentric position, GCRS axes
    Vec observer_bary_vel{};            // observer's velocity (Earth's heliocentric + rotation), au/day
    Vec earth_helio_au{};               // Earth's heliocentric position
    Vec moon_geo_au{}, moon_geo_vel{};  // the Moon's geocentric position and velocity
    Vec east{}, north{}, up{};          // local frame in ITRS
};

Frames make_frames(const Instant& t, const Place* place) {
    Frames f{};
    // The Moon (eraMoon98, geocentric GCRS) and the Earth-Moon barycentre (eraPlan94,
    // Simon et al. 1994, heliocentric, J2000 mean equator: the GCRS within 0.02"; its
    // longitude within 6" over 1800-2050 per ERFA's documentation) give the Earth's
    // heliocentric position and velocity: E = EMB - Moon / (1 + M_E / M_M). (eraEpv00 is
    // ~0.05" but ten times slower; 6" is 0.002 degree.) TT is used for TDB (< 2 ms apart).
    double moon[2][3], emb[2][3];
    eraMoon98(t.tt1, t.tt2, moon);
    eraPlan94(t.tt1, t.tt2, 3, emb);
    Vec earth_vel{};
    for (int k = 0; k < 3; ++k) {
        f.moon_geo_au[k] = moon[0][k];
        f.moon_geo_vel[k] = moon[1][k];
        f.earth_helio_au[k] = emb[0][k] - moon[0][k] / (1.0 + kEarthMoonMassRatio);
        earth_vel[k] = emb[1][k] - moon[1][k] / (1.0 + kEarthMoonMassRatio);
    }
    // Precession-nutation IAU 2000B (within 1 mas of 2000A over 1995-2050, McCarthy & Luzum
    // 2003), the frame bias included.
    eraPnm00b(t.tt1, t.tt2, f.rbpn);
    double rc2i[3][3], rpom[3][3];
    eraC2ibpn(t.tt1, t.tt2, f.rbpn, rc2i);
    const double era = eraEra00(t.ut11, t.ut12);
    eraIr(rpom);
    eraC2tcio(rc2i, era, rpom, f.rc2t);
    Vec v_obs_gcrs{};  // au/day
    if (place) {
        // Observer's position and velocity in the CIRS (ITRS turned by the Earth rotation
        // angle), in m and m/s, then to the GCRS.
        double pv[2][3];
        eraPvtob(place->longitude_deg * ERFA_DD2R, place->latitude_deg * ERFA_DD2R, place->height_m, 0.0, 0.0,
                 0.0, era, pv);
        double pv_gcrs[2][3];
        eraTrxpv(rc2i, pv, pv_gcrs);
        for (int k = 0; k < 3; ++k) {
            f.observer_gcrs_au[k] = pv_gcrs[0][k] / ERFA_DAU;
            v_obs_gcrs[k] = pv_gcrs[1][k] * ERFA_DAYSEC / ERFA_DAU;
        }
        const double lat = place->latitude_deg * ERFA_DD2R, lon = place->longitude_deg * ERFA_DD2R;
        f.east = {-std::sin(lon), std::cos(lon), 0.0};
        f.north = {-std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat)};
        f.up = {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
    }
    // The Sun's own motion about the barycentre (~ 13 m/s) changes the aberration by 0.01":
    // the heliocentric velocity stands for the barycentric one.
    f.observer_bary_vel = add(earth_vel, v_obs_gcrs);
    return f;
}

// Apparent direction (GCRS axes) of a body at `topocentric_au` (GCRS axes, already at its
// light-time position) from the observer: relativistic aberration (eraAb) with the
// observer's barycentric velocity.
Vec aberrate(const Frames& f, const Vec& topocentric_au) {
    Vec v = scale(f.observer_bary_vel, 1.0 / kC_au_day);
    const double bm1 = std::sqrt(1.0 - dot(v, v));
    const double sun_distance = norm(add(f.earth_helio_au, f.observer_gcrs_au));
    Vec pnat = unit(topocentric_au), ppr{};
    eraAb(pnat.data(), v.data(), sun_distance, bm1, ppr.data());
    return unit(ppr);
}

double wrap360(double deg) {
    double a = std::fmod(deg, 360.0);
    if (a < 0.0) a += 360.0;
    return a >= 360.0 ? 0.0 : a;
}

CelestialPosition horizontal(const Frames& f, const Vec& apparent_gcrs, double distance_au,
                             double body_radius_m, const Place& place) {
    CelestialPosition out;
    const Vec date = mul(f.rbpn, apparent_gcrs);
    out.right_ascension_deg = wrap360(std::atan2(date[1], date[0]) * ERFA_DR2D);
    out.declination_deg = std::asin(std::clamp(date[2], -1.0, 1.0)) * ERFA_DR2D;
    const Vec itrs = mul(f.rc2t, apparent_gcrs);
    const double e = dot(itrs, f.east), n = dot(itrs, f.north), u = dot(itrs, f.up);
    out.airless_elevation_deg = std::asin(std::clamp(u, -1.0, 1.0)) * ERFA_DR2D;
    out.azimuth_deg = wrap360(std::atan2(e, n) * ERFA_DR2D);
    out.elevation_deg =
        out.airless_elevation_deg +
        refraction_deg(out.airless_elevation_deg, place.effective_pressure_hpa(), place.temperature_c);
    out.distance_m = distance_au * ERFA_DAU;
    out.angular_radius_deg = std::asin(std::min(1.0, body_radius_m / out.distance_m)) * ERFA_DR2D;
    const double el = out.elevation_deg * ERFA_DD2R, az = out.azimuth_deg * ERFA_DD2R;
    out.direction_enu = {std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el)};
    return out;
}

// The moon's position from the observer (GCRS axes, au) at the moment its light, arriving
// at the observer at t, left it: the vector moon(t - tau) - observer(t) =
// [geo_moon(t - tau) + earth(t - tau)] - [earth(t) + obs(t)], with
// earth(t - tau) = earth(t) - tau v_earth (tau ~ 1.3 s: linear motion is exact enough).
// The aberration by v_earth then cancels most of the -tau v_earth term, as it must.
// (The light-time vector's length is no distance: the Earth's 30 km/s over 1.3 s change it
// by up to 40 km. `geometric_au` gets the moon's true distance from the observer at t.)
Vec moon_topocentric_au(const Frames& f, double* geometric_au) {
    *geometric_au = norm(sub(f.moon_geo_au, f.observer_gcrs_au));
    Vec topo = sub(f.moon_geo_au, f.observer_gcrs_au);
    for (int iteration = 0; iteration < 2; ++iteration) {
        const double tau = norm(topo) / kC_au_day;  // days
        topo =
            sub(sub(f.moon_geo_au, scale(add(f.moon_geo_vel, f.observer_bary_vel), tau)), f.observer_gcrs_au);
    }
    return topo;
}

// The rotation GCRS -> east/north/up: rows are the local axes in the GCRS.
void gcrs_to_enu(const Frames& f, double (&r)[3][3]) {
    for (int k = 0; k < 3; ++k) {
        Vec axis{};
        for (int j = 0; j < 3; ++j) axis[j] = f.rc2t[j][k];  // column k of GCRS -> ITRS
        r[0][k] = dot(axis, f.east);
        r[1][k] = dot(axis, f.north);
        r[2][k] = dot(axis, f.up);
    }
}

}  // namespace

void Place::validate() const {
    require_in_range("latitude_deg", latitude_deg, -90.0, 90.0, "degrees");
    require_in_range("longitude_deg", longitude_deg, -180.0, 180.0, "degrees");
    require_in_range("height_m", height_m, -500.0, 100000.0, "m");
    require_finite("pressure_hpa", pressure_hpa);
    if (pressure_hpa >= 0.0) require_in_range("pressure_hpa", pressure_hpa, 0.0, 1100.0, "hPa");
    require_in_range("temperature_c", temperature_c, -90.0, 60.0, "degrees C");
}

double Place::effective_pressure_hpa() const {
    if (pressure_hpa >= 0.0) return pressure_hpa;
    // ISA (ISO 2533): troposphere lapse 6.5 K/km from 288.15 K, isothermal 216.65 K above
    // 11 km.
    const double h = std::max(height_m, -500.0);
    if (h <= 11000.0) return 1013.25 * std::pow(1.0 - 2.25577e-5 * h, 5.25588);
    return 226.32 * std::exp(-(h - 11000.0) / 6341.62);
}

double refraction_deg(double h, double pressure_hpa, double temperature_c) {
    if (!(pressure_hpa > 0.0)) return 0.0;
    const auto saemundsson = [](double x) {
        // R in arcminutes for the true altitude x (degrees); +0.0019279' makes R(90) = 0
        // (Meeus, ch. 16).
        const double arg = (x + 10.3 / (x + 5.11)) * ERFA_DD2R;
        return 1.02 / std::tan(arg) + 0.0019279;
    };
    const double factor = (pressure_hpa / 1010.0) * (283.0 / (273.0 + temperature_c));
    double r_arcmin = 0.0;
    if (h >= -1.0)
        r_arcmin = saemundsson(std::min(h, 90.0));
    else if (h > -3.0)
        r_arcmin = saemundsson(-1.0) * (h + 3.0) / 2.0;
    return std::max(0.0, r_arcmin * factor / 60.0);
}

SunAndMoon sun_and_moon(const Instant& when, const Place& where) {
    where.validate();
    if (!std::isfinite(when.tt_jd()) || !std::isfinite(when.ut1_jd()))
        throw InvalidArgument("time", "must be a finite moment");
    const Frames f = make_frames(when, &where);
    SunAndMoon out;
    out.tt_jd = when.tt_jd();
    out.ut1_jd = when.ut1_jd();
    out.delta_t_s = when.delta_t_s();

    // Sun: geocentric = -(Earth heliocentric). Its barycentric motion over the 8.3 min of
    // light time (~ 13 m/s, 6 km) is 0.01": the light time needs no correction, the Earth's
    // motion during it is the aberration.
    const Vec sun_topo = sub(scale(f.earth_helio_au, -1.0), f.observer_gcrs_au);
    out.sun = horizontal(f, aberrate(f, sun_topo), norm(sun_topo), kSunRadius_m, where);

    double moon_distance_au = 0.0;
    const Vec moon_topo = moon_topocentric_au(f, &moon_distance_au);
    out.moon = horizontal(f, aberrate(f, moon_topo), moon_distance_au, kMoonRadius_m, where);

    // Phase: the angle at the moon between the sun and the observer (geometric vectors).
    const Vec moon_to_sun = sub(sun_topo, moon_topo), moon_to_observer = scale(moon_topo, -1.0);
    const double c = dot(unit(moon_to_sun), unit(moon_to_observer));
    out.moon_phase_angle_deg = std::acos(std::clamp(c, -1.0, 1.0)) * ERFA_DR2D;
    out.moon_illuminated_fraction = 0.5 * (1.0 + c);
    out.moon_irradiance_ratio = moon_irradiance_ratio(
        std::min(180.0, out.moon_phase_angle_deg), moon_distance_au * ERFA_DAU, norm(moon_to_sun) * ERFA_DAU);
    // Waxing or waning: the moon's ecliptic longitude minus the sun's, of date.
    const double eps = eraObl06(when.tt1, when.tt2);
    const auto ecliptic_longitude = [&](const Vec& gcrs) {
        const Vec d = mul(f.rbpn, gcrs);
        return std::atan2(d[1] * std::cos(eps) + d[2] * std::sin(eps), d[0]);
    };
    out.moon_age_angle_deg =
        wrap360((ecliptic_longitude(moon_topo) - ecliptic_longitude(sun_topo)) * ERFA_DR2D);
    // Sun as seen from the moon, in the local frame (GCRS -> ITRS -> east/north/up).
    const Vec s = mul(f.rc2t, unit(moon_to_sun));
    out.sun_from_moon_enu = {dot(s, f.east), dot(s, f.north), dot(s, f.up)};
    return out;
}

std::vector<std::array<double, 3>> apparent_star_directions(const Instant& when, const Place& where,
                                                            std::span<const std::array<double, 3>> icrs) {
    where.validate();
    if (!std::isfinite(when.tt_jd()) || !std::isfinite(when.ut1_jd()))
        throw InvalidArgument("time", "must be a finite moment");
    const Frames f = make_frames(when, &where);
    double r[3][3];
    gcrs_to_enu(f, r);
    const double pressure = where.effective_pressure_hpa();
    std::vector<std::array<double, 3>> out(icrs.size());
    for (std::size_t i = 0; i < icrs.size(); ++i) {
        // The ICRS axes are the GCRS's for directions (a star's light-time is not needed).
        const Vec enu = mul(r, aberrate(f, icrs[i]));
        const double airless = std::asin(std::clamp(enu[2], -1.0, 1.0)) * ERFA_DR2D;
        const double el = (airless + refraction_deg(airless, pressure, where.temperature_c)) * ERFA_DD2R;
        const double h = std::hypot(enu[0], enu[1]);
        const double ce = std::cos(el);
        out[i] = h > 0.0 ? std::array<double, 3>{ce * enu[0] / h, ce * enu[1] / h, std::sin(el)}
                         : std::array<double, 3>{0.0, 0.0, enu[2] > 0.0 ? 1.0 : -1.0};
    }
    return out;
}

GeocentricPosition geocentric_moon(const Instant& when) {
    if (!std::isfinite(when.tt_jd())) throw InvalidArgument("time", "must be a finite moment");
    const Frames f = make_frames(when, nullptr);
    double distance_au = 0.0;
    const Vec topo = moon_topocentric_au(f, &distance_au);
    const Vec date = mul(f.rbpn, aberrate(f, topo));
    GeocentricPosition out;
    out.right_ascension_deg = wrap360(std::atan2(date[1], date[0]) * ERFA_DR2D);
    out.declination_deg = std::asin(std::clamp(date[2], -1.0, 1.0)) * ERFA_DR2D;
    out.distance_m = distance_au * ERFA_DAU;
    return out;
}

EclipticFrame ecliptic_frame(const Instant& when, const Place& where) {
    where.validate();
    if (!std::isfinite(when.tt_jd()) || !std::isfinite(when.ut1_jd()))
        throw InvalidArgument("time", "must be a finite moment");
    const Frames f = make_frames(when, &where);
    double r[3][3], ecm[3][3];
    gcrs_to_enu(f, r);
    eraEcm06(when.tt1, when.tt2, ecm);  // GCRS -> ecliptic of date
    EclipticFrame out;
    // ecliptic = ecm * GCRS = ecm * r^T * enu.
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            double s = 0.0;
            for (int j = 0; j < 3; ++j) s += ecm[i][j] * r[k][j];
            out.enu_to_ecliptic[std::size_t(i)][std::size_t(k)] = s;
        }
    const Vec sun = mul(ecm, aberrate(f, sub(scale(f.earth_helio_au, -1.0), f.observer_gcrs_au)));
    out.sun_longitude_deg = wrap360(std::atan2(sun[1], sun[0]) * ERFA_DR2D);
    return out;
}

}  // namespace welkin
