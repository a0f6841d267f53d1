// SPDX-License-Identifier: Apache-2.0
// Civil time -> TT and UT1 (include/welkin/astro/time.hpp), with ERFA's calendar and
// leap-second functions.
#include "welkin/astro/time.hpp"

#include <cctype>
#include <cmath>
#include <string>

#include <erfa.h>
#include <erfam.h>
#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {
namespace {

bool is_leap_year(int y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

int days_in_month(int y, int m) {
    static constexpr int days[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    return m == 2 && is_leap_year(y) ? 29 : days[m - 1];
}

// Reads exactly `n` digits at `pos` (advancing it); false if they are not there.
bool read_digits(const std::string& s, std::size_t& pos, int n, int& value) {
    if (pos + std::size_t(n) > s.size()) return false;
    value = 0;
    for (int i = 0; i < n; ++i) {
        const char c = s[pos + std::size_t(i)];
        if (!std::isdigit(static_cast<unsigned char>(c))) return false;
        value = value * 10 + (c - '0');
    }
    pos += std::size_t(n);
    return true;
}

bool read_char(const std::string& s, std::size_t& pos, char c) {
    if (pos < s.size() && s[pos] == c) {
        ++pos;
        return true;
    }
    return false;
}

}  // namespace

void CivilTime::validate(const std::string& parameter) const {
    const auto fail = [&](const std::string& what) { throw InvalidArgument(parameter, what); };
    if (year < kFirstYear || year > kLastYear)
        fail(fmt::format("year must be in [{}, {}], got {}", kFirstYear, kLastYear, year));
    if (month < 1 || month > 12) fail(fmt::format("month must be in [1, 12], got {}", month));
    if (day < 1 || day > days_in_month(year, month))
        fail(fmt::format("day must be in [1, {}] for {:04d}-{:02d}, got {}", days_in_month(year, month), year,
                         month, day));
    if (hour < 0 || hour > 23) fail(fmt::format("hour must be in [0, 23], got {}", hour));
    if (minute < 0 || minute > 59) fail(fmt::format("minute must be in [0, 59], got {}", minute));
    if (!std::isfinite(second) || second < 0.0 || second >= 60.0)
        fail(fmt::format("second must be in [0, 60), got {}", second));
    if (utc_offset_minutes < -14 * 60 || utc_offset_minutes > 14 * 60)
        fail(fmt::format("UTC offset must be within -14:00 and +14:00, got {} minutes", utc_offset_minutes));
}

CivilTime parse_iso8601(const std::string& text, const std::string& parameter) {
    const auto fail = [&] {
        throw InvalidArgument(parameter, fmt::format("expected an ISO 8601 date-time with its UTC offset, "
                                                     "YYYY-MM-DDTHH:MM[:SS[.s]](Z|+HH:MM|-HH:MM), "
                                                     "e.g. 2026-06-21T21:30:00+02:00; got '{}'",
                                                     text.size() > 64 ? text.substr(0, 64) + "..." : text));
    };
    CivilTime t;
    std::size_t p = 0;
    if (!read_digits(text, p, 4, t.year) || !read_char(text, p, '-') || !read_digits(text, p, 2, t.month) ||
        !read_char(text, p, '-') || !read_digits(text, p, 2, t.day))
        fail();
    if (!read_char(text, p, 'T') && !read_char(text, p, 't') && !read_char(text, p, ' ')) fail();
    if (!read_digits(text, p, 2, t.hour) || !read_char(text, p, ':') || !read_digits(text, p, 2, t.minute))
        fail();
    t.second = 0.0;
    if (read_char(text, p, ':')) {
        int whole = 0;
        if (!read_digits(text, p, 2, whole)) fail();
        t.second = whole;
        if (read_char(text, p, '.') || read_char(text, p, ',')) {
            double scale = 0.1;
            const std::size_t start = p;
            while (p < text.size() && std::isdigit(static_cast<unsigned char>(text[p])) && p - start < 9) {
                t.second += (text[p] - '0') * scale;
                scale *= 0.1;
                ++p;
            }
            if (p == start) fail();
        }
    }
    if (read_char(text, p, 'Z') || read_char(text, p, 'z')) {
        t.utc_offset_minutes = 0;
    } else {
        int sign = 0;
        if (read_char(text, p, '+'))
            sign = 1;
        else if (read_char(text, p, '-'))
            sign = -1;
        else
            fail();
        int hh = 0, mm = 0;
        if (!read_digits(text, p, 2, hh)) fail();
        if (p < text.size()) {
            read_char(text, p, ':');
            if (!read_digits(text, p, 2, mm) || mm > 59) fail();
        }
        t.utc_offset_minutes = sign * (hh * 60 + mm);
    }
    if (p != text.size()) fail();
    t.validate(parameter);
    return t;
}

CivilTime to_utc(const CivilTime& time, const std::string& parameter) {
    time.validate(parameter);
    CivilTime t = time;
    int minutes = t.hour * 60 + t.minute - t.utc_offset_minutes;
    t.utc_offset_minutes = 0;
    int shift = 0;
    while (minutes < 0) minutes += 1440, --shift;
    while (minutes >= 1440) minutes -= 1440, ++shift;
    t.hour = minutes / 60;
    t.minute = minutes % 60;
    for (; shift > 0; --shift) {
        if (++t.day > days_in_month(t.year, t.month)) {
            t.day = 1;
            if (++t.month > 12) t.month = 1, ++t.year;
        }
    }
    for (; shift < 0; ++shift) {
        if (--t.day < 1) {
            if (--t.month < 1) t.month = 12, --t.year;
            t.day = days_in_month(t.year, t.month);
        }
    }
    return t;
}

double delta_t_espenak_meeus(double y) {
    // Espenak & Meeus 2006, "Polynomial expressions for Delta T", the 1900-1961 intervals.
    if (y < 1920.0) {
        const double t = y - 1900.0;
        return -2.79 + 1.494119 * t - 0.0598939 * t * t + 0.0061966 * t * t * t - 0.000197 * t * t * t * t;
    }
    if (y < 1941.0) {
        const double t = y - 1920.0;
        return 21.20 + 0.84493 * t - 0.076100 * t * t + 0.0020936 * t * t * t;
    }
    const double t = y - 1950.0;
    return 29.07 + 0.407 * t - t * t / 233.0 + t * t * t / 2547.0;
}

double Instant::delta_t_s() const { return ((tt1 - ut11) + (tt2 - ut12)) * ERFA_DAYSEC; }

Instant Instant::from_tt(double tt_jd, double delta_t_s) {
    if (!std::isfinite(tt_jd) || !std::isfinite(delta_t_s))
        throw InvalidArgument("tt_jd", "must be finite (and so must delta_t_s)");
    Instant i;
    i.tt1 = std::floor(tt_jd) + 0.5;
    if (i.tt1 > tt_jd) i.tt1 -= 1.0;
    i.tt2 = tt_jd - i.tt1;
    i.ut11 = i.tt1;
    i.ut12 = i.tt2 - delta_t_s / ERFA_DAYSEC;
    return i;
}

Instant Instant::from_civil(const CivilTime& time, const std::string& parameter) {
    const CivilTime u = to_utc(time, parameter);
    const int y = u.year, m = u.month, d = u.day, hour = u.hour, minute = u.minute;
    if (y < kFirstYear || y > kLastYear)
        throw InvalidArgument(
            parameter, fmt::format("the UTC year must be in [{}, {}], got {}", kFirstYear, kLastYear, y));
    Instant i;
    if (y < 1960) {
        // Before UTC: the time is UT (UT1); TT from Delta T.
        if (eraDtf2d("UT1", y, m, d, hour, minute, time.second, &i.ut11, &i.ut12) != 0)
            throw InvalidArgument(parameter, "is not a valid time of day");
        const double dt = delta_t_espenak_meeus(y + (m - 0.5) / 12.0);
        i.tt1 = i.ut11;
        i.tt2 = i.ut12 + dt / ERFA_DAYSEC;
        return i;
    }
    double u1 = 0.0, u2 = 0.0, tai1 = 0.0, tai2 = 0.0;
    // eraDtf2d and eraUtctai return +1 for a "dubious year" (past the leap-second table's
    // release by some years): the last known TAI - UTC is then used, as every
    // almanac does for the future.
    if (eraDtf2d("UTC", y, m, d, hour, minute, time.second, &u1, &u2) < 0 ||
        eraUtctai(u1, u2, &tai1, &tai2) < 0 || eraTaitt(tai1, tai2, &i.tt1, &i.tt2) < 0 ||
        eraUtcut1(u1, u2, 0.0, &i.ut11, &i.ut12) < 0)
        throw InvalidArgument(parameter, "is not a valid UTC time");
    return i;
}

}  // namespace welkin
