// SPDX-License-Identifier: Apache-2.0
// A moment in time for the positions of the sun and the moon: civil date and time (UTC, or
// local time with its offset from UTC) turned into the two time scales the ephemerides
// need: Terrestrial Time (TT, the argument of the orbits) and UT1 (the Earth's rotation
// angle).
//
// From 1960 on, the civil time is UTC: UTC -> TAI through the leap-second table of ERFA
// (eraDat, the IAU SOFA table) and TAI -> TT = TAI + 32.184 s. UT1 is taken equal to UTC
// (|UT1 - UTC| < 0.9 s by the definition of UTC, at most 0.004 degree of the sky's
// rotation). Before 1960 (UTC did not exist) the civil time is read as UT1 and
// TT = UT1 + Delta T from Espenak & Meeus's polynomials ("Five Millennium Canon of Solar
// Eclipses", NASA TP-2006-214141, section 2.6; also eclipse.gsfc.nasa.gov/SEhelp/deltatpoly2004.html).
#pragma once

#include <string>

namespace welkin {

// Accepted years: about the range over which ERFA's planetary (eraPlan94) and lunar
// (eraMoon98) series hold their stated accuracy.
inline constexpr int kFirstYear = 1900, kLastYear = 2100;

// Civil date and time with its offset from UTC (local = UTC + offset).
struct CivilTime {
    int year = 2000, month = 1, day = 1;
    int hour = 12, minute = 0;
    double second = 0.0;
    int utc_offset_minutes = 0;  // e.g. +120 for 21:30+02:00; in [-14 h, +14 h]

    // Throws InvalidArgument naming `parameter` (the caller's name for the time) with the
    // field and its accepted range: year in [1900, 2100], a real calendar day, hour 0-23,
    // minute 0-59, second in [0, 60), offset within +-14:00.
    void validate(const std::string& parameter = "time") const;
};

// ISO 8601 date-time with a UTC offset: "2026-06-21T21:30:00+02:00", "2026-06-21T19:30Z",
// "2026-06-21 19:30:00.5+00:00", "2026-06-21T21:30+0200". The offset is required ('Z' or
// +-HH[:MM]): a time without one would be ambiguous. Throws InvalidArgument naming
// `parameter`, with the expected form, for anything else.
CivilTime parse_iso8601(const std::string& text, const std::string& parameter = "time");

// The civil time moved to UTC (offset 0), the calendar carried across days and years (the
// year may then leave [1900, 2100] by one). Validates first (InvalidArgument naming
// `parameter`).
CivilTime to_utc(const CivilTime& time, const std::string& parameter = "time");

// The moment on the two time scales, each as a two-part Julian date (sum = JD; the split
// keeps the precision of the time of day, as ERFA expects).
struct Instant {
    double tt1 = 0.0, tt2 = 0.0;    // Terrestrial Time
    double ut11 = 0.0, ut12 = 0.0;  // UT1

    double tt_jd() const { return tt1 + tt2; }
    double ut1_jd() const { return ut11 + ut12; }
    // TT - UT1 in seconds (Delta T).
    double delta_t_s() const;

    // From civil time (validated: InvalidArgument naming `parameter`).
    static Instant from_civil(const CivilTime& time, const std::string& parameter = "time");
    // From a TT Julian date, with UT1 = TT - delta_t_s (the published test cases give both).
    static Instant from_tt(double tt_jd, double delta_t_s);
};

// Espenak & Meeus (2006) Delta T = TT - UT1 in seconds for 1900 <= year < 1961 (the
// polynomial of the year's interval; decimal_year = year + (month - 0.5) / 12).
double delta_t_espenak_meeus(double decimal_year);

}  // namespace welkin
