// SPDX-License-Identifier: Apache-2.0
// The sun and the moon as seen from a place on the Earth at a moment: apparent,
// topocentric horizontal coordinates (elevation, azimuth clockwise from north), distances,
// and the moon's phase.
//
// The astronomy is ERFA's (the IAU SOFA library, BSD-3 licensed, Debian's liberfa): the
// Moon's geocentric position (eraMoon98, Meeus 1998's ELP-2000/82 truncation, ~ 4" over
// 1963-2013 against ELP/MPP02), the Earth-Moon barycentre's heliocentric orbit (eraPlan94,
// Simon et al. 1994, ~ 6"), IAU 2000B precession-nutation (eraPnm00b, 1 mas), the Earth
// rotation angle (eraEra00) and the observer's position and
// velocity on the WGS84 ellipsoid (eraPvtob). src/astro/positions.cpp composes them as an
// almanac does (Kaplan 2005, "The IAU Resolutions on Astronomical Reference Systems...",
// USNO Circular 179, ch. 7; the order of eraApco/eraAtciq):
//   1. topocentric position: body (geocentric, GCRS axes) minus the observer's geocentric
//      position, the body taken at the time its light left it (light time);
//   2. aberration by the observer's barycentric velocity (annual + diurnal, eraAb);
//   3. GCRS -> true equator of date (precession-nutation) and -> the Earth's frame (Earth
//      rotation angle; polar motion, < 0.3", neglected) -> the local east/north/up frame of
//      the geodetic latitude and longitude;
//   4. atmospheric refraction (Saemundsson 1986, Sky & Telescope 72, 70; Meeus,
//      "Astronomical Algorithms" 2nd ed., eq. 16.4; the form NREL's SPA uses, Reda &
//      Andreas 2004 eq. 42), scaled by pressure and temperature.
// The moon's parallax (up to ~ 1 degree) comes from step 1, the sun's (8.8") as well.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "welkin/astro/time.hpp"

namespace welkin {

// A place on the Earth (WGS84 geodetic), with the air that refracts the light.
struct Place {
    double latitude_deg = 0.0;   // north positive, [-90, 90]
    double longitude_deg = 0.0;  // east positive, [-180, 180]
    double height_m = 0.0;       // above the ellipsoid, [-500, 100000]
    // Air at the observer for refraction. Pressure < 0: the ISA standard atmosphere's
    // pressure at height_m (1013.25 hPa at sea level); 0 turns refraction off.
    double pressure_hpa = -1.0;   // [0, 1100] or negative for the default
    double temperature_c = 10.0;  // [-90, 60]

    // Throws InvalidArgument naming the field ("latitude_deg", ...) and its range.
    void validate() const;
    // The pressure refraction uses (the default resolved).
    double effective_pressure_hpa() const;
};

struct CelestialPosition {
    double elevation_deg = 0.0;          // apparent (refracted), above the horizontal plane
    double azimuth_deg = 0.0;            // clockwise from north (east = 90), [0, 360)
    double airless_elevation_deg = 0.0;  // the same without refraction
    double distance_m = 0.0;             // from the observer
    double angular_radius_deg = 0.0;     // of the disc, at that distance
    // Topocentric apparent right ascension and declination (true equator and equinox of
    // date), without refraction.
    double right_ascension_deg = 0.0, declination_deg = 0.0;
    // Unit vector towards the apparent (refracted) body in the local frame: x east,
    // y north, z up.
    std::array<double, 3> direction_enu{0.0, 0.0, 1.0};
};

struct SunAndMoon {
    CelestialPosition sun, moon;
    // Angle sun - moon - observer (0 at full moon, 180 at new moon) and the illuminated
    // fraction of the moon's disc, (1 + cos phase angle) / 2 (Meeus eq. 48.1).
    double moon_phase_angle_deg = 0.0;
    double moon_illuminated_fraction = 0.0;
    // The moon's phase: the sun's elongation from the moon as the observer's
    // longitude difference, in [0, 360): 0 new, 90 first quarter, 180 full, 270 last
    // quarter (waxing below 180).
    double moon_age_angle_deg = 0.0;
    // The moon's irradiance at the top of the atmosphere over the sun's at 1 au
    // (moon_irradiance_ratio of astro/moonlight.hpp for this phase angle and these
    // distances): a moon lamp's strength is a sun lamp's at 1 au times this, times the air's
    // transmittance towards the moon.
    double moon_irradiance_ratio = 0.0;
    // Direction from the moon towards the sun in the local east/north/up frame (unit): what
    // lights the moon's disc (the observer sees the moon's hemisphere facing -moon direction).
    std::array<double, 3> sun_from_moon_enu{0.0, 0.0, 1.0};
    double tt_jd = 0.0, ut1_jd = 0.0, delta_t_s = 0.0;
};

// Everything above for one moment and one place. Throws InvalidArgument from
// Place::validate. Microseconds (one precession-nutation evaluation per call).
SunAndMoon sun_and_moon(const Instant& when, const Place& where);

// Apparent topocentric directions (x east, y north, z up, refracted by refraction_deg) of
// objects at infinite distance, the stars, from their ICRS unit vectors (at the moment:
// proper motion already applied): the aberration by the observer's barycentric velocity,
// precession-nutation and the Earth's rotation of sun_and_moon (the same frames). Light
// deflection by the sun (1.75" at its limb, < 0.005" beyond 90 degrees from it) and the
// annual parallax (< 0.8") are neglected. Throws InvalidArgument from Place::validate.
std::vector<std::array<double, 3>> apparent_star_directions(const Instant& when, const Place& where,
                                                            std::span<const std::array<double, 3>> icrs);

// The ecliptic as seen from a place at a moment, for the light that lies along it (the
// zodiacal light, night/night_glow.hpp): the rotation from the local frame (x east,
// y north, z up) to the geocentric ecliptic and equinox of date (ERFA's eraEcm06: the
// IAU 2006 ecliptic of date from the GCRS, with the frame bias and precession), and the
// sun's apparent ecliptic longitude of date. Nutation (< 20") and the aberration of the
// directions (< 21") are left out of the rotation: the zodiacal light varies over
// degrees. Throws InvalidArgument from Place::validate.
struct EclipticFrame {
    // ecliptic = enu_to_ecliptic * enu (row-major; x towards the equinox, z the north
    // ecliptic pole).
    std::array<std::array<double, 3>, 3> enu_to_ecliptic{{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
    double sun_longitude_deg = 0.0;  // [0, 360)
};
EclipticFrame ecliptic_frame(const Instant& when, const Place& where);

// The moon's geocentric apparent right ascension and declination (true equator and
// equinox of date) and distance: what Meeus' example 47.a tabulates.
struct GeocentricPosition {
    double right_ascension_deg = 0.0, declination_deg = 0.0, distance_m = 0.0;
};
GeocentricPosition geocentric_moon(const Instant& when);

// Refraction in degrees for a true (airless) elevation, Saemundsson's formula scaled by
// (P / 1010 hPa) (283 K / T) and offset so that it is 0 at the zenith. Below -1 degree it
// fades linearly to 0 at -3 degrees, so that the apparent elevation stays continuous and
// increasing through sunset (the formula has no meaning there; below the horizon the
// atmosphere model, not this, decides what the sky looks like).
double refraction_deg(double true_elevation_deg, double pressure_hpa, double temperature_c);

// Solar and lunar radii used for the discs (IAU 2015 nominal solar radius; the Moon's
// mean radius, IAU WGCCRE).
inline constexpr double kSunRadius_m = 695700e3;
inline constexpr double kMoonRadius_m = 1737.4e3;

}  // namespace welkin
