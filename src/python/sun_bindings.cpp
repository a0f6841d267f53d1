// SPDX-License-Identifier: Apache-2.0
// welkin.sun: the sun as seen from the observer (include/welkin/atmosphere/sun.hpp), so that a sun
// lamp and the sky agree.
#include <memory>

#include "bindings.hpp"
#include <fmt/format.h>

#include "welkin/atmosphere/sun_disc.hpp"
#include "welkin/color/color.hpp"

namespace welkin::python {
namespace {

// The core's SunRadiometry plus the wavelengths it is sampled at.
struct Sun {
    SunRadiometry radiometry;
    std::vector<double> wavelengths_nm;
    std::shared_ptr<const SunDisc> disc;          // the disc model (sun_disc.hpp)
    ColorSpace color_space = ColorSpace::Rec709;  // of the *_rgb values
};

// (rows, 6) read-only float64 array.
py::array_t<double> coefficient_rows(const std::vector<std::array<double, 6>>& rows) {
    py::array_t<double> a({py::ssize_t(rows.size()), py::ssize_t(6)});
    auto v = a.mutable_unchecked<2>();
    for (std::size_t i = 0; i < rows.size(); ++i)
        for (int k = 0; k < 6; ++k) v(py::ssize_t(i), k) = rows[i][std::size_t(k)];
    a.attr("flags").attr("writeable") = false;
    return a;
}

SunDisc::Rgb disc_rgb(const Sun& sun) {
    const SpectrumToRgb to_rgb(sun.wavelengths_nm, 0.0, sun.color_space);
    return sun.disc->rgb(to_rgb.matrix(), to_rgb.luminance_weights());
}

// Sunlight in linear RGB of sun.color_space: the three-sample conversion with lambda power 0 (the
// sun's own spectrum between the samples), see color.hpp.
py::array_t<double> direct_irradiance_rgb(const Sun& sun) {
    const SpectrumToRgb to_rgb(sun.wavelengths_nm, 0.0, sun.color_space);
    const std::vector<float> spectrum(sun.radiometry.direct_irradiance.begin(),
                                      sun.radiometry.direct_irradiance.end());
    const std::array<double, 3> rgb = to_rgb.convert(spectrum);
    return to_readonly_array({rgb.begin(), rgb.end()});
}

}  // namespace

void register_sun(py::module_& m) {
    py::class_<Sun>(m, "SunRadiometry", R"doc(
The sun seen from the observer; returned by welkin.sun().

Attributes (per wavelength of wavelengths_nm unless noted)
  transmittance          observer -> sun through the atmosphere, at the disc
                         centre (0 when the ground blocks it)
  direct_irradiance      normal-incidence spectral irradiance of the disc at the
                         observer, W m^-2 nm^-1: solar irradiance x transmittance
                         x the visible fraction of the disc
  visible_fraction       fraction of the disc above the horizon (a float)
  direct_irradiance_rgb  direct_irradiance in linear RGB of color_space (Rec.709
                         unless welkin.sun() was given another), W m^-2, (3,)
                         (CIE 1931, no 683 lm/W factor; lambda power 0 between
                         three samples) -- a Blender sun lamp's strength/colour
  wavelengths_nm         the wavelengths, nm
  color_space            "rec709", "rec2020" or "acescg": of the *_rgb values

The disc (one model for every renderer; include/welkin/atmosphere/sun_disc.hpp):
  angular_radius_rad     the disc's angular radius alpha, rad
  solid_angle_sr         2 pi (1 - cos alpha)
  mean_radiance          direct_irradiance / (visible_fraction x solid_angle_sr),
                         W m^-2 sr^-1 nm^-1: its integral over the visible disc
                         is direct_irradiance
  centre_radiance        radiance at the disc centre (limb-darkened peak)
  limb_coefficients      (C, 6): Neckel & Labs 1994 a_0..a_5, radiance at angle
                         rho from the centre = centre_radiance x sum_k a_k mu^k,
                         mu = sqrt(1 - (sin rho / sin alpha)^2)
  centre_radiance_rgb    (3,) the same in linear RGB of color_space, W m^-2 sr^-1
  limb_coefficients_rgb  (3, 6) so that the RGB disc is exactly
                         centre_radiance_rgb[j] x sum_k b[j, k] mu^k; each
                         row a convex combination of limb_coefficients' rows
                         (a positive profile darkening to the limb), the
                         disc's integral the lamp's colour
)doc")
        .def_property_readonly("transmittance",
                               [](const Sun& s) { return to_readonly_array(s.radiometry.transmittance); })
        .def_property_readonly("direct_irradiance",
                               [](const Sun& s) { return to_readonly_array(s.radiometry.direct_irradiance); })
        .def_property_readonly("visible_fraction", [](const Sun& s) { return s.radiometry.visible_fraction; })
        .def_property_readonly("direct_irradiance_rgb", &direct_irradiance_rgb)
        .def_property_readonly("color_space", [](const Sun& s) { return color_space_name(s.color_space); })
        .def_property_readonly("wavelengths_nm",
                               [](const Sun& s) { return to_readonly_array(s.wavelengths_nm); })
        .def_property_readonly("angular_radius_rad",
                               [](const Sun& s) { return s.disc->angular_radius_rad(); })
        .def_property_readonly("solid_angle_sr", [](const Sun& s) { return s.disc->solid_angle_sr(); })
        .def_property_readonly("mean_radiance",
                               [](const Sun& s) { return to_readonly_array(s.disc->mean_radiance()); })
        .def_property_readonly("centre_radiance",
                               [](const Sun& s) { return to_readonly_array(s.disc->centre_radiance()); })
        .def_property_readonly("limb_coefficients",
                               [](const Sun& s) { return coefficient_rows(s.disc->limb_coefficients()); })
        .def_property_readonly("centre_radiance_rgb",
                               [](const Sun& s) {
                                   const auto c = disc_rgb(s).centre_radiance;
                                   return to_readonly_array({c.begin(), c.end()});
                               })
        .def_property_readonly("limb_coefficients_rgb",
                               [](const Sun& s) {
                                   const auto b = disc_rgb(s).limb_coefficients;
                                   return coefficient_rows({b.begin(), b.end()});
                               })
        .def("__repr__", [](const Sun& s) {
            return fmt::format(
                "<welkin.SunRadiometry transmittance=[{:.6g}] "
                "direct_irradiance=[{:.6g}] W m^-2 nm^-1 visible_fraction={:.6g}>",
                fmt::join(s.radiometry.transmittance, ", "), fmt::join(s.radiometry.direct_irradiance, ", "),
                s.radiometry.visible_fraction);
        });

    m.def(
        "sun",
        [](Atmosphere atmosphere, double altitude_m, const py::object& sun_direction,
           const std::string& color_space) {
            const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};
            Sun sun;
            sun.color_space = color_space_from_name(color_space);
            {
                py::gil_scoped_release release;
                sun.disc = std::make_shared<const SunDisc>(atmosphere, observer);
                sun.radiometry = sun.disc->radiometry();
            }
            sun.wavelengths_nm = atmosphere.wavelengths_nm;
            return sun;
        },
        py::arg("atmosphere"), py::arg("altitude_m"), py::arg("sun_direction"), py::kw_only(),
        py::arg("color_space") = "rec709", R"doc(
Sun radiometry at an observer altitude_m (m) above the ground, for a sun in
sun_direction (vector towards the sun, Z up; normalised here). Returns a
welkin.SunRadiometry: transmittance, direct_irradiance (W m^-2 nm^-1),
visible_fraction, direct_irradiance_rgb (W m^-2) in the linear RGB of
color_space ("rec709", "rec2020" or "acescg", color_space.hpp). Raises
ValueError for altitude_m < 0, a zero or NaN sun_direction, an invalid
atmosphere or an unknown color_space.
)doc");
}

}  // namespace welkin::python
