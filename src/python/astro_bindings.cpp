// SPDX-License-Identifier: Apache-2.0
// welkin.sun_and_moon: the apparent sun and moon from a place and a moment
// (include/welkin/astro/positions.hpp), as the dict `welkin sun --time` prints under
// "place_and_time" (one schema: include/welkin/astro/json.hpp).
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "bindings.hpp"
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <pybind11/stl.h>

#include "welkin/astro/json.hpp"
#include "welkin/astro/moonlight.hpp"
#include "welkin/astro/positions.hpp"
#include "welkin/astro/time.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/clouds/density.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/color_space.hpp"
#include "welkin/night/moonlit_sky.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/night/stars.hpp"
#include "welkin/sky/method.hpp"

namespace welkin::python {

std::vector<Star> to_stars(const py::array_t<double>& stars) {
    if (stars.ndim() != 2 || stars.shape(1) != 5)
        throw InvalidArgument("stars", "must be an (N, 5) array: x, y, z, V, B-V per star");
    const auto s = stars.unchecked<2>();
    std::vector<Star> list(std::size_t(stars.shape(0)));
    for (py::ssize_t i = 0; i < stars.shape(0); ++i)
        list[std::size_t(i)] = Star{{s(i, 0), s(i, 1), s(i, 2)}, s(i, 3), s(i, 4)};
    return list;
}

namespace {
std::string time_text(const py::object& time);
}  // namespace

NightGlowOptions night_glow_options(const py::object& time, double latitude_deg, double longitude_deg,
                                    double height_m, double north_deg, bool airglow, bool zodiacal_light) {
    require_in_range("north_deg", north_deg, -360.0, 360.0, "degrees");
    NightGlowOptions glow;
    glow.airglow = airglow;
    glow.zodiacal_light = zodiacal_light;
    if (time.is_none()) return glow;
    const Instant when = Instant::from_civil(parse_iso8601(time_text(time), "time"), "time");
    EclipticFrame frame = ecliptic_frame(when, Place{latitude_deg, longitude_deg, height_m});
    // The image's frame is the local one turned by north_deg about z (a scene's, as
    // stars_at's directions are turned): enu = Rz(-north) image.
    const double c = std::cos(north_deg * kDegree), s = std::sin(north_deg * kDegree);
    for (auto& row : frame.enu_to_ecliptic) {
        const double x = row[0], y = row[1];
        row[0] = c * x - s * y;
        row[1] = s * x + c * y;
    }
    glow.ecliptic = frame;
    return glow;
}

namespace {

// A str, or anything with isoformat() (an aware datetime.datetime).
std::string time_text(const py::object& time) {
    if (py::isinstance<py::str>(time)) return time.cast<std::string>();
    if (py::hasattr(time, "isoformat")) return py::str(time.attr("isoformat")()).cast<std::string>();
    throw InvalidArgument("time", "must be an ISO 8601 string or a timezone-aware datetime");
}

constexpr const char* kSkyImageAtDoc = R"doc(
The sky of a place and a moment, as `welkin sky --time --latitude --longitude`
renders it: the sun's sky and disc at the sun's apparent position, plus the
moon's light (its sky: the same atmosphere lit by the moon, brightness from
Allen's magnitude-phase law) and its disc with its phase, energy-exact.

    img = welkin.sky_image_at(atm, "2026-06-21T23:30:00+02:00", 48.8566, 2.3522, 2048)

Same image layout, units, exposure and errors as sky_image (+Y north, +X east).
time, latitude_deg, longitude_deg, height_m: as in sun_and_moon; altitude_m: the
observer above the ground (as in sky_image); discs=False leaves both discs out
(when sun and moon lamps light the scene). stars=True adds the stars of V <= 7
of the Hipparcos catalogue at their apparent places, dimmed and reddened by the
air towards each, energy-exact (welkin.star_image). night_glow=True adds the
night sky's own light: airglow and the zodiacal light along the moment's
ecliptic, dimmed by the air (welkin.night_glow_image). clouds: as in sky_image
(a welkin.CloudLayer or any CloudDensity, default lighting): lit by the sun and
by the moon (the same march for a "sun" in the moon's direction, times its
brightness; left out while the sun is up), with the discs, the stars and the
night glow seen through them, dimmed by their transmittance.
)doc";

py::array_t<float> sky_image_at(Atmosphere atmosphere, const py::object& time, double latitude_deg,
                                double longitude_deg, int width, const std::string& method,
                                const std::string& output, double height_m, double altitude_m, bool discs,
                                double exposure, bool ground, bool stars, bool night_glow,
                                const py::object& progress, std::shared_ptr<const CloudDensity> clouds) {
    require_progress_callback(progress);
    const std::string text = time_text(time);
    SkyImageOptions options;
    options.sun_disc = discs;
    options.ground = ground;
    options.exposure = exposure;
    options.output = parse_output(output);
    options.clouds = std::move(clouds);
    const std::unique_ptr<SkyMethod> sky = make_sky_method(method, SkyOptions{});
    const CivilTime civil = parse_iso8601(text, "time");
    const Place place{latitude_deg, longitude_deg, height_m};
    const Instant when = Instant::from_civil(civil, "time");
    const SunAndMoon positions = sun_and_moon(when, place);
    const auto& d = positions.sun.direction_enu;
    const Observer observer = Observer{altitude_m, {d[0], d[1], d[2]}}.validated();
    Moon moon = moon_at(positions);
    moon.disc = discs;
    SkyImage image;
    run_cancellable(
        [&](Progress* p) {
            image = render_equirect_sky_with_moon(*sky, atmosphere, observer, moon, width, options, p);
            if (night_glow) {
                NightGlowOptions glow;
                glow.ecliptic = ecliptic_frame(when, place);
                add_night_glow(image, atmosphere, observer, options, glow);
            }
            if (stars) add_stars(image, atmosphere, observer, stars_at(when, place), options);
        },
        progress);
    const std::size_t channels = image.channels();
    return to_image_array(std::move(image.pixels), image.width, image.height, channels);
}

// A Moon from the binding's arguments (their names in the errors).
Moon moon_from(const py::object& moon_direction, const py::object& sun_from_moon, double angular_radius_rad,
               double irradiance_ratio) {
    Moon moon;
    moon.direction = to_dvec3(moon_direction, "moon_direction");
    moon.sun_from_moon = to_dvec3(sun_from_moon, "sun_from_moon");
    moon.angular_radius_rad = angular_radius_rad;
    moon.irradiance_ratio = irradiance_ratio;
    for (const auto& [v, name] :
         {std::pair{moon.direction, "moon_direction"}, std::pair{moon.sun_from_moon, "sun_from_moon"}})
        if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) ||
            (v.x == 0.0 && v.y == 0.0 && v.z == 0.0))
            throw InvalidArgument(name, "must be a finite non-zero vector");
    moon.validate();  // the radius and the ratio, named moon.<field>
    return moon;
}

py::array_t<float> moon_disc_image(const Atmosphere& atmosphere, double altitude_m,
                                   const py::object& moon_direction, const py::object& sun_from_moon,
                                   double angular_radius_rad, double irradiance_ratio, int width,
                                   const std::string& output, double exposure) {
    if (!(exposure > 0.0 && exposure <= 1e6))
        throw InvalidArgument("exposure", fmt::format("must be in (0, 1e6], got {}", exposure));
    const Moon moon = moon_from(moon_direction, sun_from_moon, angular_radius_rad, irradiance_ratio);
    const SkyImageOptions::Output out = parse_output(output);
    std::vector<float> pixels;
    {
        py::gil_scoped_release release;
        atmosphere.validate();
        const Observer observer = Observer{altitude_m, moon.direction}.validated();
        pixels = moon_disc_pixels(atmosphere, observer, moon, width, out);
    }
    for (float& v : pixels) v *= float(exposure);
    const std::size_t channels = out == SkyImageOptions::Output::Rgb ? 3 : atmosphere.channels();
    return to_image_array(std::move(pixels), width, width / 2, channels);
}

py::dict moon_disc_py(const Atmosphere& atmosphere, double altitude_m, const py::object& moon_direction,
                      const py::object& sun_from_moon, double angular_radius_rad, double irradiance_ratio,
                      double exposure, const std::string& color_space) {
    if (!(exposure > 0.0 && exposure <= 1e6))
        throw InvalidArgument("exposure", fmt::format("must be in (0, 1e6], got {}", exposure));
    const Moon moon = moon_from(moon_direction, sun_from_moon, angular_radius_rad, irradiance_ratio);
    const ColorSpace space = color_space_from_name(color_space);
    MoonDiscModel model;
    {
        py::gil_scoped_release release;
        model = moon_disc_model(atmosphere, Observer{altitude_m, moon.direction}.validated(), moon);
    }
    // Moonlight has the sun's spectrum: the sun's conversion (lambda power 0), as the disc's
    // pixels and the moon lamp take it.
    const SpectrumToRgb to_rgb(atmosphere.wavelengths_nm, 0.0, space);
    const std::vector<double> mat = to_rgb.matrix();
    const std::size_t nc = model.radiance_scale.size();
    std::vector<double> rgb(3, 0.0), spectral(nc);
    for (std::size_t c = 0; c < nc; ++c) {
        spectral[c] = model.radiance_scale[c] * exposure;
        for (std::size_t k = 0; k < 3; ++k) rgb[k] += mat[k * nc + c] * spectral[c];
    }
    py::dict out;
    out["radiance_scale"] = to_readonly_array(spectral);
    out["radiance_scale_rgb"] = to_readonly_array(rgb);
    out["relative_integral_sr"] = model.relative_integral_sr;
    out["phase_angle_rad"] = model.phase_angle_rad;
    out["color_space"] = color_space_name(space);
    return out;
}

py::array_t<double> moon_disc_relative_radiance_py(const py::array_t<double>& views,
                                                   const py::object& moon_direction,
                                                   const py::object& sun_from_moon,
                                                   double angular_radius_rad) {
    const Moon moon = moon_from(moon_direction, sun_from_moon, angular_radius_rad, 0.0);
    if (views.ndim() != 2 || views.shape(1) != 3) throw InvalidArgument("views", "must be an (N, 3) array");
    const glm::dvec3 m = glm::normalize(moon.direction), s = glm::normalize(moon.sun_from_moon);
    const auto v = views.unchecked<2>();
    py::array_t<double> out(views.shape(0));
    auto o = out.mutable_unchecked<1>();
    for (py::ssize_t i = 0; i < views.shape(0); ++i) {
        glm::dvec3 d{v(i, 0), v(i, 1), v(i, 2)};
        const double l = glm::length(d);
        if (!(l > 0.0) || !std::isfinite(l))
            throw InvalidArgument("views", fmt::format("row {} is not a direction", i));
        d /= l;
        o(i) = moon_disc_relative_radiance_far({d.x, d.y, d.z}, {m.x, m.y, m.z}, moon.angular_radius_rad,
                                               {s.x, s.y, s.z});
    }
    return out;
}

py::array_t<double> star_catalogue() {
    const auto stars = hipparcos_stars();
    py::array_t<double> out({py::ssize_t(stars.size()), py::ssize_t(6)});
    auto o = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < stars.size(); ++i) {
        const CatalogueStar& s = stars[i];
        const double row[6] = {s.ra_deg, s.dec_deg, s.pm_ra_mas_yr, s.pm_dec_mas_yr, s.v_mag, s.b_v};
        for (py::ssize_t k = 0; k < 6; ++k) o(py::ssize_t(i), k) = row[k];
    }
    return out;
}

py::array_t<double> stars_at_py(const py::object& time, double latitude_deg, double longitude_deg,
                                double height_m, double faintest_v) {
    const CivilTime civil = parse_iso8601(time_text(time), "time");
    const std::vector<Star> stars = stars_at(Instant::from_civil(civil, "time"),
                                             Place{latitude_deg, longitude_deg, height_m}, faintest_v);
    py::array_t<double> out({py::ssize_t(stars.size()), py::ssize_t(5)});
    auto o = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < stars.size(); ++i) {
        const Star& s = stars[i];
        const double row[5] = {s.direction.x, s.direction.y, s.direction.z, s.v_mag, s.b_v};
        for (py::ssize_t k = 0; k < 5; ++k) o(py::ssize_t(i), k) = row[k];
    }
    return out;
}

void require_exposure(double exposure) {
    if (!(exposure > 0.0 && exposure <= 1e6))
        throw InvalidArgument("exposure", fmt::format("must be in (0, 1e6], got {}", exposure));
}

py::array_t<float> star_image(const Atmosphere& atmosphere, const py::array_t<double>& stars, int width,
                              const std::string& output, double altitude_m, double exposure,
                              const std::string& color_space) {
    require_exposure(exposure);
    const ColorSpace space = color_space_from_name(color_space);
    const std::vector<Star> list = to_stars(stars);
    const SkyImageOptions::Output out = parse_output(output);
    std::vector<float> pixels;
    {
        py::gil_scoped_release release;
        atmosphere.validate();
        const Observer observer = Observer{altitude_m, {0.0, 0.0, 1.0}}.validated();
        pixels = star_pixels(atmosphere, observer, list, width, out, space);
    }
    for (float& v : pixels) v *= float(exposure);
    const std::size_t channels = out == SkyImageOptions::Output::Rgb ? 3 : atmosphere.channels();
    return to_image_array(std::move(pixels), width, width / 2, channels);
}

py::array_t<float> night_glow_image(const Atmosphere& atmosphere, int width, const std::string& output,
                                    double altitude_m, double exposure, const std::string& color_space,
                                    const py::object& time, double latitude_deg, double longitude_deg,
                                    double height_m, double north_deg, bool airglow, bool zodiacal_light) {
    require_exposure(exposure);
    const ColorSpace space = color_space_from_name(color_space);
    const SkyImageOptions::Output out = parse_output(output);
    const NightGlowOptions glow =
        night_glow_options(time, latitude_deg, longitude_deg, height_m, north_deg, airglow, zodiacal_light);
    std::vector<float> pixels;
    {
        py::gil_scoped_release release;
        atmosphere.validate();
        const Observer observer = Observer{altitude_m, {0.0, 0.0, 1.0}}.validated();
        pixels = night_glow_pixels(atmosphere, observer, width, out, space, glow);
    }
    for (float& v : pixels) v *= float(exposure);
    const std::size_t channels = out == SkyImageOptions::Output::Rgb ? 3 : atmosphere.channels();
    return to_image_array(std::move(pixels), width, width / 2, channels);
}

// The stars and the night glow, each alone.
void register_night_parts(py::module_& m) {
    m.def("star_catalogue", &star_catalogue, R"doc(
The compiled-in star catalogue, brightest first: an (N, 6) float64 array of ICRS
right ascension and declination (degrees, epoch J1991.25), proper motion
(mu_alpha cos delta, mu_delta; mas/yr), Johnson V and B-V, for the Hipparcos
stars of V <= 7 (van Leeuwen 2007; V from Hp by Bessell 2000).
)doc");
    m.def("stars_at", &stars_at_py, py::arg("time"), py::arg("latitude_deg"), py::arg("longitude_deg"),
          py::kw_only(), py::arg("height_m") = 0.0, py::arg("faintest_v") = 7.0, R"doc(
The catalogue's stars of V <= faintest_v as seen from a place at a moment: an
(N, 5) float64 array of the apparent direction (x east, y north, z up; with
aberration, precession-nutation and refraction, as sun_and_moon), V and B-V.
Stars below the horizon are included.
)doc");
    m.def("star_image", &star_image, py::arg("atmosphere"), py::arg("stars"), py::arg("width"),
          py::arg("output") = "rgb", py::kw_only(), py::arg("altitude_m") = 0.0, py::arg("exposure") = 1.0,
          py::arg("color_space") = "rec709", R"doc(
The stars' light alone as an equirectangular (height, width, channels) float32
image: each star of `stars` (an (N, 5) array as stars_at returns) dimmed by the
air's transmittance towards it and spread over the 4 pixels around it so that the
sum of radiance x pixel solid angle is its irradiance, times exposure. Same units
and colour spaces as sky_image. Directions in any frame (Z up): the scene's, for a
host that turns the sky.
)doc");
    m.def("night_glow_image", &night_glow_image, py::arg("atmosphere"), py::arg("width"),
          py::arg("output") = "rgb", py::kw_only(), py::arg("altitude_m") = 0.0, py::arg("exposure") = 1.0,
          py::arg("color_space") = "rec709", py::arg("time") = py::none(), py::arg("latitude_deg") = 0.0,
          py::arg("longitude_deg") = 0.0, py::arg("height_m") = 0.0, py::arg("north_deg") = 0.0,
          py::arg("airglow") = true, py::arg("zodiacal_light") = true,
          R"doc(
The night sky's own light alone (include/welkin/night/night_glow.hpp), as an
equirectangular (height, width, channels) float32 image times exposure; 0 below
the horizon. Same units and colour spaces as sky_image. Its parts:
airglow=True: the upper atmosphere's glow (O I 557.7 nm, Na D, O I 630/636 nm and
its continuum) from a layer 97 km up, brightening towards the horizon by van
Rhijn's factor; zodiacal_light=True: Leinert et al. 1998's zodiacal light by
helioecliptic longitude and ecliptic latitude, the sun's light slightly
reddened. Both dimmed by the air towards each direction.

time, latitude_deg, longitude_deg, height_m: the moment and place (as in
sun_and_moon) that put the ecliptic and the sun in the sky; time=None: the
zodiacal light at its darkest (the ecliptic pole's) everywhere. north_deg: the
image's frame turned about the vertical as stars_at's directions are turned by
a host (x' = cos n x - sin n y, y' = sin n x + cos n y).
)doc");
}

// The moon's disc as a formula, for hosts that draw it (the add-on's world nodes).
void register_moon_disc(py::module_& m) {
    m.def("moon_disc", &moon_disc_py, py::arg("atmosphere"), py::arg("altitude_m"), py::arg("moon_direction"),
          py::arg("sun_from_moon"), py::arg("angular_radius_rad"), py::arg("irradiance_ratio"), py::kw_only(),
          py::arg("exposure") = 1.0, py::arg("color_space") = "rec709", R"doc(
The moon's disc as a formula of the view direction, for a host that draws it
itself (include/welkin/night/moonlit_sky.hpp, MoonDiscModel): where the view v is
above the horizon its radiance is
    radiance_scale_rgb x moon_disc_relative_radiance(v, ...)
(Lommel-Seeliger seen from afar, zero on the night side: the phase), and its
integral over the disc is the moon's irradiance through the air (the sun's at
1 au x irradiance_ratio x the transmittance towards the moon, times exposure),
as the disc of sky_image_at and moon_disc_image. Returns a dict:
radiance_scale (per wavelength) and radiance_scale_rgb (linear RGB of
color_space, the sun's conversion), W m^-2 sr^-1 (nm^-1) per unit relative
radiance; relative_integral_sr (the disc's integral of the relative radiance:
sin^2(radius) pi/2 Phi(phase), Lommel-Seeliger's phase function); phase_angle_rad;
color_space. Arguments as moon_disc_image's.
)doc");
    m.def("moon_disc_relative_radiance", &moon_disc_relative_radiance_py, py::arg("views"),
          py::arg("moon_direction"), py::arg("sun_from_moon"), py::arg("angular_radius_rad"), R"doc(
The disc's relative radiance (include/welkin/astro/moonlight.hpp,
moon_disc_relative_radiance_far) for an (N, 3) array of view directions
(normalised here): mu0 / (mu0 + mu) on the lit, visible disc, 0 elsewhere; times
moon_disc's radiance_scale_rgb it is the disc's radiance.
)doc");
}

}  // namespace

void register_astro(py::module_& m) {
    m.def(
        "sun_and_moon",
        [](py::object time, double latitude_deg, double longitude_deg, double height_m,
           std::optional<double> pressure_hpa, double temperature_c) {
            const std::string text = time_text(time);
            nlohmann::ordered_json j;
            {
                py::gil_scoped_release release;
                const CivilTime civil = parse_iso8601(text, "time");
                Place place{latitude_deg, longitude_deg, height_m, pressure_hpa.value_or(-1.0),
                            temperature_c};
                if (pressure_hpa) require_in_range("pressure_hpa", *pressure_hpa, 0.0, 1100.0, "hPa");
                const SunAndMoon sky = sun_and_moon(Instant::from_civil(civil, "time"), place);
                j = place_and_time_json(civil, place, sky);
            }
            return py::module_::import("json").attr("loads")(j.dump());
        },
        py::arg("time"), py::arg("latitude_deg"), py::arg("longitude_deg"), py::arg("height_m") = 0.0,
        py::arg("pressure_hpa") = py::none(), py::arg("temperature_c") = 10.0, R"doc(
The apparent (topocentric, refracted) sun and moon seen from a place at a moment.

time           ISO 8601 with its UTC offset, "2026-06-21T21:30:00+02:00" or
               "...Z", or a timezone-aware datetime; years 1900-2100
latitude_deg   geodetic, north positive, [-90, 90]
longitude_deg  east positive, [-180, 180]
height_m       above the WGS84 ellipsoid, [-500, 100000]
pressure_hpa   air pressure for refraction, [0, 1100] (0: no refraction);
               None: the standard atmosphere's at height_m
temperature_c  air temperature for refraction, [-90, 60]

Returns a dict, the "place_and_time" object of `welkin sun --time` (docs/reference.md):
sun/moon each with elevation_deg, azimuth_deg (clockwise from north),
airless_elevation_deg, distance_m, angular_radius_deg, right_ascension_deg,
declination_deg and direction (x east, y north, z up); the moon also with
phase_angle_deg, illuminated_fraction, age_angle_deg (0 new, 180 full) and
sun_direction_from_moon. Accuracy: the sun within 0.01 degree, the moon within
0.05 degree (ERFA; tested against NREL SPA, Meeus and JPL DE421 via Skyfield).
Raises ValueError naming the parameter for a bad time or place.
)doc");

    m.def("moon_disc_image", &moon_disc_image, py::arg("atmosphere"), py::arg("altitude_m"),
          py::arg("moon_direction"), py::arg("sun_from_moon"), py::arg("angular_radius_rad"),
          py::arg("irradiance_ratio"), py::arg("width"), py::arg("output") = "rgb", py::kw_only(),
          py::arg("exposure") = 1.0, R"doc(
The moon's disc alone, as the equirectangular image sky_image_at adds for it
(include/welkin/night/moonlit_sky.hpp): its phase lit from sun_from_moon
(Lommel-Seeliger across the disc), energy-exact (its pixels sum, times their
solid angles, to the moon's irradiance through the air: the sun's at 1 au x
irradiance_ratio x the transmittance towards the moon), hidden behind the
ground, times exposure. Directions in any frame (Z up): the scene's, for a
host that turns the sky. Same layout and units as sky_image.

moon_direction, sun_from_moon  the "direction" and "sun_direction_from_moon" of
                               sun_and_moon's moon (turned alike)
angular_radius_rad             the moon's apparent radius, [1e-4, 0.05]
irradiance_ratio               the moon's "irradiance_ratio", [0, 1e-3]
)doc");

    register_night_parts(m);
    register_moon_disc(m);
    m.def("sky_image_at", &sky_image_at, py::arg("atmosphere"), py::arg("time"), py::arg("latitude_deg"),
          py::arg("longitude_deg"), py::arg("width"), py::arg("method") = "lut", py::arg("output") = "rgb",
          py::kw_only(), py::arg("height_m") = 0.0, py::arg("altitude_m") = 0.0, py::arg("discs") = true,
          py::arg("exposure") = 1.0, py::arg("ground") = true, py::arg("stars") = true,
          py::arg("night_glow") = true, py::arg("progress") = py::none(), py::arg("clouds") = py::none(),
          kSkyImageAtDoc);
}

}  // namespace welkin::python
