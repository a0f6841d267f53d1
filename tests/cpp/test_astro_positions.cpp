// SPDX-License-Identifier: Apache-2.0
// The sun and the moon from a place and a moment (welkin/astro/): against the published
// worked cases, the refraction formula against Bennett's independent fit, the time
// scales, and bad input. The comparison over many dates and places with an independent
// ephemeris (JPL DE421 through Skyfield) is tests/python/test_place_and_time.py.
#include <chrono>
#include <cmath>

#include "invalid_argument_testing.hpp"
#include <gtest/gtest.h>

#include "welkin/astro/json.hpp"
#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"

namespace welkin {
namespace {

using test::parameter_of;

// Angular difference of two azimuths, degrees.
double azimuth_difference(double a, double b) {
    double d = std::fmod(std::abs(a - b), 360.0);
    return d > 180.0 ? 360.0 - d : d;
}

// NREL's Solar Position Algorithm, Reda & Andreas 2004 (NREL/TP-560-34302, Table A4.1):
// Golden, Colorado, 2003-10-17 12:30:30 local (UTC-7), 39.742476 N, 105.1786 W,
// 1830.14 m, 820 hPa, 11 C. Topocentric zenith 50.11162, azimuth 194.34024 (eastward from
// north), topocentric right ascension 202.22704 and declination -9.316179. SPA's own
// accuracy is +-0.0003 degree; the bound for the sun is 0.01 degree. (SPA used
// Delta T = 67 s; the leap seconds give 64.184 s: 3 s of the sun's motion is 3e-5 degree.)
TEST(AstroPositions, SunMatchesSpaPublishedCase) {
    const CivilTime t{2003, 10, 17, 12, 30, 30.0, -7 * 60};
    const Place golden{39.742476, -105.1786, 1830.14, 820.0, 11.0};
    const SunAndMoon r = sun_and_moon(Instant::from_civil(t), golden);
    EXPECT_NEAR(90.0 - r.sun.elevation_deg, 50.11162, 0.01);
    EXPECT_LT(azimuth_difference(r.sun.azimuth_deg, 194.34024), 0.01);
    EXPECT_NEAR(r.sun.right_ascension_deg, 202.22704, 0.01);
    EXPECT_NEAR(r.sun.declination_deg, -9.316179, 0.01);
    EXPECT_NEAR(r.delta_t_s, 64.184, 1e-6);  // 32 leap seconds + 32.184 s in 2003
    // The sun's distance that day (SPA: R = 0.9965422974 au from the Earth's centre); the
    // observer is nearer by about the Earth's radius times the sine of the sun's elevation.
    const double geocentric_m =
        r.sun.distance_m + 6371e3 * std::sin(r.sun.airless_elevation_deg * M_PI / 180.0);
    EXPECT_NEAR(geocentric_m / 149597870.7e3, 0.9965422974, 2e-6);
}

// Meeus, "Astronomical Algorithms" (2nd ed., 1998), example 47.a: 1992 April 12, 0h TD,
// Delta T 59 s: apparent geocentric right ascension 134.688470, declination 13.768368,
// distance 368409.7 km. The bound for the moon is 0.05 degree.
TEST(AstroPositions, MoonMatchesMeeusExample47a) {
    const GeocentricPosition m = geocentric_moon(Instant::from_tt(2448724.5, 59.0));
    EXPECT_NEAR(m.right_ascension_deg, 134.688470, 0.05);
    EXPECT_NEAR(m.declination_deg, 13.768368, 0.05);
    EXPECT_NEAR(m.distance_m / 1e3, 368409.7, 1.0);
}

// Meeus example 48.a, the same moment: illuminated fraction k = 0.6786 seen from the
// Earth's centre. From a place on the Earth the moon's parallax (< 1.0 degree) changes the
// phase angle i by at most that, so k = (1 + cos i) / 2 by at most 0.5 sin(i) 1.0 degree
// = 0.008 (i = 69.08 degrees): within 0.01 from anywhere.
TEST(AstroPositions, MoonPhaseMatchesMeeusExample48a) {
    const Instant t = Instant::from_tt(2448724.5, 59.0);
    for (const Place& p : {Place{0.0, 0.0, 0.0}, Place{52.0, 13.4, 40.0}, Place{-33.9, 151.2, 0.0}}) {
        const SunAndMoon r = sun_and_moon(t, p);
        EXPECT_NEAR(r.moon_illuminated_fraction, 0.6786, 0.01);
        EXPECT_NEAR(r.moon_illuminated_fraction,
                    0.5 * (1.0 + std::cos(r.moon_phase_angle_deg * M_PI / 180.0)), 1e-12);
        // Waxing (between new and full: first quarter was 1992 April 10).
        EXPECT_GT(r.moon_age_angle_deg, 90.0);
        EXPECT_LT(r.moon_age_angle_deg, 180.0);
    }
}

// Saemundsson's formula (true -> apparent) against Bennett's (1982, J. Navigation 35, 255;
// apparent -> true: R = cot(h0 + 7.31 / (h0 + 4.4)) arcmin), two independent fits of the
// same refraction tables: Meeus ch. 16 gives their consistency as about 0.1', from the
// horizon up (below it, neither formula is a measurement).
TEST(AstroPositions, RefractionAgreesWithBennett) {
    for (double h0 = 0.0; h0 <= 90.0; h0 += 0.25) {  // apparent altitude
        const double bennett = (1.0 / std::tan((h0 + 7.31 / (h0 + 4.4)) * M_PI / 180.0)) / 60.0;
        const double true_h = h0 - bennett;
        EXPECT_NEAR(refraction_deg(true_h, 1010.0, 10.0), bennett, 0.2 / 60.0) << "apparent altitude " << h0;
    }
    EXPECT_NEAR(refraction_deg(90.0, 1010.0, 10.0), 0.0, 1e-6);
    EXPECT_EQ(refraction_deg(10.0, 0.0, 10.0), 0.0);  // no air, no refraction
    // Scales with density: half the pressure, half the refraction.
    EXPECT_NEAR(refraction_deg(5.0, 505.0, 10.0), 0.5 * refraction_deg(5.0, 1010.0, 10.0), 1e-12);
    // Apparent elevation continuous and increasing through sunset and below.
    double previous = -5.0 + refraction_deg(-5.0, 1013.25, 10.0);
    for (int k = 1; k <= 10000; ++k) {
        const double h = -5.0 + 0.001 * k;
        const double apparent = h + refraction_deg(h, 1013.25, 10.0);
        EXPECT_GT(apparent, previous) << "true elevation " << h;
        EXPECT_LT(apparent - previous, 0.001 * 1.5) << "true elevation " << h;
        previous = apparent;
    }
}

TEST(AstroPositions, TimeScales) {
    // 2017-01-01 00:00:00 UTC follows the last leap second: TT - UTC = 37 + 32.184 s.
    const Instant a = Instant::from_civil(parse_iso8601("2017-01-01T00:00:00Z"));
    EXPECT_NEAR((a.tt_jd() - 2457754.5) * 86400.0, 69.184, 1e-4);
    // The offset: 21:30+02:00 is 19:30Z, including across a year boundary.
    const Instant b = Instant::from_civil(parse_iso8601("2026-06-21T21:30:00+02:00"));
    const Instant c = Instant::from_civil(parse_iso8601("2026-06-21T19:30:00Z"));
    EXPECT_EQ(b.tt_jd(), c.tt_jd());
    EXPECT_EQ(format_iso8601_utc(parse_iso8601("2027-01-01T01:15:00+03:30")), "2026-12-31T21:45:00Z");
    EXPECT_EQ(format_iso8601_utc(parse_iso8601("2024-02-28T22:00:00-05:00")), "2024-02-29T03:00:00Z");
    EXPECT_EQ(format_iso8601(parse_iso8601("2026-06-21 21:30:15.25+0200")),
              "2026-06-21T21:30:15.250000+02:00");
    // Before 1960: the time is UT, TT = UT + Delta T (Espenak & Meeus; ~24 s in 1930).
    const Instant d = Instant::from_civil(parse_iso8601("1930-06-01T00:00:00Z"));
    EXPECT_NEAR(d.delta_t_s(), delta_t_espenak_meeus(1930.0 + 5.5 / 12.0), 1e-4);
    EXPECT_NEAR(d.delta_t_s(), 24.0, 1.0);
    // The polynomials meet at their joints (within the 0.1 s Delta T is known to there).
    EXPECT_NEAR(delta_t_espenak_meeus(1920.0 - 1e-9), delta_t_espenak_meeus(1920.0), 0.1);
    EXPECT_NEAR(delta_t_espenak_meeus(1941.0 - 1e-9), delta_t_espenak_meeus(1941.0), 0.1);
}

TEST(AstroPositions, BadInputNamesTheParameter) {
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-06-21T21:30:00", "--time"); }), "--time");  // no offset
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-13-01T00:00Z", "--time"); }), "--time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-02-29T00:00Z", "--time"); }),
              "--time");  // not a leap year
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-04-31T00:00Z"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-06-21T24:00Z"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-06-21T23:60Z"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-06-21T23:00:60Z"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-06-21T23:00+15:00"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("1899-12-31T23:00Z"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2101-01-01T00:00Z"); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601(""); }), "time");
    EXPECT_EQ(parameter_of([] { parse_iso8601("2026-06-21T21:30:00+02:00junk"); }), "time");
    // The local year is in range but UTC's is not.
    EXPECT_EQ(parameter_of([] { Instant::from_civil(parse_iso8601("2100-12-31T23:00-02:00")); }), "time");
    const Instant t = Instant::from_civil(parse_iso8601("2026-06-21T12:00Z"));
    EXPECT_EQ(parameter_of([&] { sun_and_moon(t, Place{90.5, 0.0, 0.0}); }), "latitude_deg");
    EXPECT_EQ(parameter_of([&] { sun_and_moon(t, Place{NAN, 0.0, 0.0}); }), "latitude_deg");
    EXPECT_EQ(parameter_of([&] { sun_and_moon(t, Place{0.0, 181.0, 0.0}); }), "longitude_deg");
    EXPECT_EQ(parameter_of([&] { sun_and_moon(t, Place{0.0, 0.0, -1000.0}); }), "height_m");
    EXPECT_EQ(parameter_of([&] { sun_and_moon(t, Place{0.0, 0.0, 0.0, 2000.0}); }), "pressure_hpa");
    EXPECT_EQ(parameter_of([&] { sun_and_moon(t, Place{0.0, 0.0, 0.0, -1.0, 100.0}); }), "temperature_c");
    // The poles and the date line are places like any other.
    for (const Place& p : {Place{90.0, 0.0, 0.0}, Place{-90.0, 180.0, 0.0}, Place{0.0, -180.0, 8848.0}}) {
        const SunAndMoon r = sun_and_moon(t, p);
        EXPECT_TRUE(std::isfinite(r.sun.elevation_deg) && std::isfinite(r.moon.azimuth_deg));
    }
}

// The direction vector is the elevation and azimuth (x east, y north, z up), and the
// sun is where the json says it is.
TEST(AstroPositions, DirectionAndJsonAgree) {
    const CivilTime t = parse_iso8601("2026-06-21T21:30:00+02:00");
    const Place paris{48.8566, 2.3522, 35.0};
    const SunAndMoon r = sun_and_moon(Instant::from_civil(t), paris);
    for (const CelestialPosition* p : {&r.sun, &r.moon}) {
        const auto& d = p->direction_enu;
        EXPECT_NEAR(std::asin(d[2]) * 180.0 / M_PI, p->elevation_deg, 1e-9);
        EXPECT_LT(azimuth_difference(std::atan2(d[0], d[1]) * 180.0 / M_PI, p->azimuth_deg), 1e-9);
    }
    // The sun a few degrees up in the north-west on a Paris midsummer evening; the moon's
    // disc about a quarter of a degree across at about 0.26 degree radius.
    EXPECT_GT(r.sun.elevation_deg, 0.0);
    EXPECT_LT(r.sun.elevation_deg, 10.0);
    EXPECT_GT(r.sun.azimuth_deg, 290.0);
    EXPECT_LT(r.sun.azimuth_deg, 320.0);
    EXPECT_NEAR(r.moon.angular_radius_deg, 0.259, 0.02);
    const auto j = place_and_time_json(t, paris, r);
    EXPECT_EQ(j["utc"], "2026-06-21T19:30:00Z");
    EXPECT_EQ(j["sun"]["elevation_deg"].get<double>(), r.sun.elevation_deg);
    EXPECT_EQ(j["moon"]["illuminated_fraction"].get<double>(), r.moon_illuminated_fraction);
}

// "Positions in microseconds": one call (both bodies, one precession-nutation) is timed
// and must stay under a millisecond even on a loaded machine (the bench, bench/bench_astro.cpp,
// gives the figure).
TEST(AstroPositions, PositionsTakeMicroseconds) {
    const Place p{48.8566, 2.3522, 35.0};
    const Instant t0 = Instant::from_civil(parse_iso8601("2026-06-21T00:00:00Z"));
    const int n = 200;
    double sink = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < n; ++i) {
        Instant t = t0;
        t.tt2 += i / 1440.0, t.ut12 += i / 1440.0;
        sink += sun_and_moon(t, p).sun.elevation_deg;
    }
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count() / n;
    EXPECT_TRUE(std::isfinite(sink));
    EXPECT_LT(us, 1000.0);
}

}  // namespace
}  // namespace welkin
