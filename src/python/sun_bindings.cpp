// welkin.sun: the sun as seen from the observer (include/welkin/sun.hpp), so that a sun
// lamp and the sky agree.
#include <fmt/format.h>

#include "bindings.hpp"
#include "welkin/color/color.hpp"
#include "welkin/atmosphere/sun.hpp"

namespace welkin::python {
namespace {

// The core's SunRadiometry plus the wavelengths it is sampled at.
struct Sun {
    SunRadiometry radiometry;
    std::vector<double> wavelengths_nm;
};

// Sunlight in linear Rec.709: the three-sample conversion with lambda power 0 (the
// sun's own spectrum between the samples), see color.hpp.
py::array_t<double> direct_irradiance_rgb(const Sun& sun) {
    const SpectrumToRgb to_rgb(sun.wavelengths_nm, 0.0);
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
  direct_irradiance_rgb  direct_irradiance in linear Rec.709, W m^-2, (3,)
                         (CIE 1931, no 683 lm/W factor; lambda power 0 between
                         three samples) -- a Blender sun lamp's strength/colour
  wavelengths_nm         the wavelengths, nm
)doc")
        .def_property_readonly("transmittance",
                               [](const Sun& s) { return to_readonly_array(s.radiometry.transmittance); })
        .def_property_readonly(
            "direct_irradiance",
            [](const Sun& s) { return to_readonly_array(s.radiometry.direct_irradiance); })
        .def_property_readonly("visible_fraction",
                               [](const Sun& s) { return s.radiometry.visible_fraction; })
        .def_property_readonly("direct_irradiance_rgb", &direct_irradiance_rgb)
        .def_property_readonly("wavelengths_nm",
                               [](const Sun& s) { return to_readonly_array(s.wavelengths_nm); })
        .def("__repr__", [](const Sun& s) {
            return fmt::format("<welkin.SunRadiometry transmittance=[{:.6g}] "
                               "direct_irradiance=[{:.6g}] W m^-2 nm^-1 visible_fraction={:.6g}>",
                               fmt::join(s.radiometry.transmittance, ", "),
                               fmt::join(s.radiometry.direct_irradiance, ", "),
                               s.radiometry.visible_fraction);
        });

    m.def(
        "sun",
        [](Atmosphere atmosphere, double altitude_m, const py::object& sun_direction) {
            const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};
            Sun sun;
            {
                py::gil_scoped_release release;
                sun.radiometry = sun_radiometry(atmosphere, observer);
            }
            sun.wavelengths_nm = atmosphere.wavelengths_nm;
            return sun;
        },
        py::arg("atmosphere"), py::arg("altitude_m"), py::arg("sun_direction"), R"doc(
Sun radiometry at an observer altitude_m (m) above the ground, for a sun in
sun_direction (vector towards the sun, Z up; normalised here). Returns a
welkin.SunRadiometry: transmittance, direct_irradiance (W m^-2 nm^-1),
visible_fraction, direct_irradiance_rgb (W m^-2). Raises ValueError for
altitude_m < 0, a zero or NaN sun_direction, or an invalid atmosphere.
)doc");
}

}  // namespace welkin::python
