// SPDX-License-Identifier: Apache-2.0
// welkin.Atmosphere, welkin.DensityProfile and welkin.DensityLayer.
//
// An Atmosphere is plain data (include/welkin/atmosphere/atmosphere.hpp). Python reads and writes its
// fields freely; nothing is checked per field, because changing the wavelengths means
// changing every spectrum with them. validate() checks the whole, and every computation
// validates again, so an inconsistent atmosphere raises ValueError naming the field
// rather than computing anything. Spectra come back as read-only float64 copies: assign
// a whole new sequence to change one.
#include <filesystem>

#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "welkin/atmosphere/aerosol.hpp"
#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"

namespace welkin::python {
namespace {

const char* phase_name(MiePhaseModel model) {
    return model == MiePhaseModel::CornetteShanks ? "cornette_shanks" : "henyey_greenstein";
}

MiePhaseModel phase_model(const std::string& name) {
    if (name == "cornette_shanks") return MiePhaseModel::CornetteShanks;
    if (name == "henyey_greenstein") return MiePhaseModel::HenyeyGreenstein;
    throw InvalidArgument("mie_phase", fmt::format("must be \"cornette_shanks\" or "
                                                   "\"henyey_greenstein\", got \"{}\"",
                                                   name));
}

// One read-write spectrum attribute: a read-only numpy copy out, any sequence in.
void spectrum_property(py::class_<Atmosphere>& cls, const char* name, std::vector<double> Atmosphere::*field,
                       const char* doc) {
    cls.def_property(
        name, [field](const Atmosphere& a) { return to_readonly_array(a.*field); },
        [field, name](Atmosphere& a, const py::object& values) { a.*field = to_vector(values, name); }, doc);
}

// Per-channel values of a core function of (channel, altitude), as a (C,) array.
template <class F>
py::array_t<double> per_channel(const Atmosphere& a, F f) {
    a.validate();  // the core indexes every spectrum by channel
    std::vector<double> v(a.channels());
    for (std::size_t c = 0; c < v.size(); ++c) v[c] = f(c);
    return to_readonly_array(v);
}

std::string layer_repr(const DensityLayer& l) {
    return fmt::format(
        "DensityLayer(width_m={}, exp_term={}, exp_scale_per_m={}, "
        "linear_per_m={}, constant={})",
        l.width_m, l.exp_term, l.exp_scale_per_m, l.linear_per_m, l.constant);
}

// DensityLayer and DensityProfile: the altitude profiles of the constituents.
void register_density_profiles(py::module_& m) {
    py::class_<DensityLayer>(m, "DensityLayer", R"doc(
One layer of a density profile (Bruneton 2017's DensityProfileLayer):

    rho(h) = exp_term * exp(exp_scale_per_m * h) + linear_per_m * h + constant,

clamped to [0, 1], for altitudes h (m) in [bottom, bottom + width_m). The last
layer of a profile extends upwards without limit (its width_m is ignored).
)doc")
        .def(py::init([](double width_m, double exp_term, double exp_scale_per_m, double linear_per_m,
                         double constant) {
                 return DensityLayer{width_m, exp_term, exp_scale_per_m, linear_per_m, constant};
             }),
             py::kw_only(), py::arg("width_m") = 0.0, py::arg("exp_term") = 0.0,
             py::arg("exp_scale_per_m") = 0.0, py::arg("linear_per_m") = 0.0, py::arg("constant") = 0.0)
        .def_readwrite("width_m", &DensityLayer::width_m, "Layer thickness, m.")
        .def_readwrite("exp_term", &DensityLayer::exp_term)
        .def_readwrite("exp_scale_per_m", &DensityLayer::exp_scale_per_m, "m^-1.")
        .def_readwrite("linear_per_m", &DensityLayer::linear_per_m, "m^-1.")
        .def_readwrite("constant", &DensityLayer::constant)
        .def("density", &DensityLayer::density, py::arg("altitude_m"),
             "Relative density (0..1) at altitude_m (m) by this layer's formula.")
        .def("__repr__", &layer_repr);

    py::class_<DensityProfile>(m, "DensityProfile", R"doc(
Vertical relative-density profile (0..1) of one constituent: a stack of
DensityLayer. A constituent's coefficients (m^-1) are its values where the
density is 1.
)doc")
        .def(py::init<std::vector<DensityLayer>>(), py::arg("layers"))
        .def_static("exponential", &DensityProfile::exponential, py::arg("scale_height_m"),
                    "rho(h) = exp(-h / scale_height_m).")
        .def_static("tent", &DensityProfile::tent, py::arg("bottom_m"), py::arg("peak_m"), py::arg("top_m"),
                    "0 at bottom_m rising linearly to 1 at peak_m, back to 0 at top_m (m).")
        .def_static("zero", &DensityProfile::zero, "Density 0 everywhere (constituent off).")
        .def_property_readonly("layers", &DensityProfile::layers, "The layers, bottom first (a copy).")
        .def_property_readonly("exponential_scale_height_m", &DensityProfile::exponential_scale_height_m,
                               "Scale height (m) if this is a single decaying exponential, "
                               "else None.")
        .def(
            "density",
            [](const DensityProfile& p, const c_array<double>& altitude_m) {
                return py::vectorize([&p](double h) { return p.density(h); })(altitude_m);
            },
            py::arg("altitude_m"), "Relative density (0..1) at altitude_m (m); a scalar or any numpy array.")
        .def("validate", &DensityProfile::validate, py::arg("parameter") = "density",
             "Raises ValueError naming `parameter` if a layer is not finite.")
        .def("__repr__", [](const DensityProfile& p) {
            std::vector<std::string> layers;
            for (const DensityLayer& l : p.layers()) layers.push_back(layer_repr(l));
            return fmt::format("DensityProfile([{}])", fmt::join(layers, ", "));
        });
}

// Atmosphere's geometry, phase, density profiles, per-wavelength coefficients at an
// altitude, copies, pickling and repr.
void bind_atmosphere_geometry_and_copies(py::class_<Atmosphere>& atmosphere) {
    atmosphere
        .def_readwrite("sun_angular_radius_rad", &Atmosphere::sun_angular_radius_rad,
                       "Angular radius of the sun's disc, rad.")
        .def_readwrite("bottom_radius_m", &Atmosphere::bottom_radius_m, "Planet (ground) radius, m.")
        .def_readwrite("top_radius_m", &Atmosphere::top_radius_m, "Radius of the top of the atmosphere, m.")
        .def_readwrite("mie_g", &Atmosphere::mie_g, "Mie phase asymmetry g, in [-0.999, 0.999].")
        .def_property(
            "mie_phase", [](const Atmosphere& a) { return phase_name(a.mie_phase); },
            [](Atmosphere& a, const std::string& name) { a.mie_phase = phase_model(name); },
            "Mie phase function: \"cornette_shanks\" or \"henyey_greenstein\".")
        .def_readwrite("rayleigh_density", &Atmosphere::rayleigh_density,
                       "DensityProfile of the Rayleigh scatterers.")
        .def_readwrite("mie_density", &Atmosphere::mie_density, "DensityProfile of the aerosols.")
        .def_readwrite("absorption_density", &Atmosphere::absorption_density,
                       "DensityProfile of the absorbing layer (ozone).")
        .def_property_readonly("atmosphere_thickness_m", &Atmosphere::atmosphere_thickness_m,
                               "top_radius_m - bottom_radius_m.")
        .def(
            "extinction",
            [](const Atmosphere& a, double altitude_m) {
                return per_channel(a, [&](std::size_t c) { return a.extinction(c, altitude_m); });
            },
            py::arg("altitude_m"),
            "Total extinction (m^-1) per wavelength at altitude_m (m) above the ground.")
        .def(
            "scattering",
            [](const Atmosphere& a, double altitude_m) {
                return per_channel(a, [&](std::size_t c) { return a.scattering(c, altitude_m); });
            },
            py::arg("altitude_m"), "Scattering (Rayleigh + Mie, m^-1) per wavelength at altitude_m (m).")
        .def(
            "copy", [](const Atmosphere& a) { return Atmosphere(a); }, "An independent copy.")
        .def("__copy__", [](const Atmosphere& a) { return Atmosphere(a); })
        .def(
            "__deepcopy__", [](const Atmosphere& a, const py::dict&) { return Atmosphere(a); },
            py::arg("memo"))
        .def(py::pickle([](const Atmosphere& a) { return a.to_json_string(); },
                        [](const std::string& text) { return Atmosphere::from_json_string(text); }))
        .def("__repr__", [](const Atmosphere& a) {
            return fmt::format(
                "<welkin.Atmosphere '{}': {} wavelengths, ground radius {} m, "
                "top {} m>",
                a.name, a.channels(), a.bottom_radius_m, a.top_radius_m);
        });
}

}  // namespace

void register_atmosphere(py::module_& m) {
    register_density_profiles(m);
    py::class_<Atmosphere> atmosphere(m, "Atmosphere", R"doc(
A planet's atmosphere: everything the sky depends on (Bruneton 2017's model).

Rayleigh scattering, Mie scattering and extinction, and an absorbing layer
(ozone), each with its own DensityProfile, over a Lambertian ground. SI units:
lengths in m, coefficients in m^-1 where the relative density is 1, solar
irradiance in W m^-2 nm^-1. Spectral attributes hold one value per wavelength
of wavelengths_nm (default 620, 560, 480, 440 nm).

Make one with Atmosphere.preset(name) or Atmosphere.from_json(path). Attributes
are read-write; spectra read back as read-only numpy copies (assign a whole new
sequence to change one). Nothing is checked per attribute: call validate() after
editing (every computation validates too, raising ValueError naming the field).
)doc");

    atmosphere
        .def_static(
            "preset",
            [](const std::string& name, const py::object& wavelengths_nm) {
                return Atmosphere::preset(name, to_vector(wavelengths_nm, "wavelengths_nm"));
            },
            py::arg("name"), py::arg("wavelengths_nm") = py::none(), R"doc(
A built-in atmosphere: one of Atmosphere.preset_names() ("clear_day", the
default, an ordinary clear day; "clear", "hazy", "polluted", "desert_dust",
"maritime"; "bruneton2017", Bruneton's validation atmosphere; "mars"; sources
in src/atmosphere/presets.cpp).

wavelengths_nm: None for the default 620, 560, 480, 440 nm, or any sequence of
wavelengths in [360, 830] nm (e.g. welkin.spectral_wavelengths_nm()) at which
the preset's spectral models are evaluated.
Raises ValueError for an unknown name or a wavelength out of range.
)doc")
        .def_static("preset_names", &Atmosphere::preset_names,
                    "Names of the built-in presets, the default (clear_day) first.")
        .def_static(
            "from_json",
            [](const std::filesystem::path& path) { return Atmosphere::from_json_file(path.string()); },
            py::arg("path"), R"doc(
Reads an atmosphere from a JSON file (schema in docs/pipelines.md, "Atmosphere JSON"; {"preset": name}
plus any fields to override). Raises ValueError naming the field (its key path)
and the file for malformed JSON, a number out of range, unknown keys or invalid
values; OSError naming the file for one it cannot read (missing, a directory or
device, larger than 64 MiB; docs/limits.md), as SceneDescription.from_json does.
)doc")
        .def_static("from_json_string", &Atmosphere::from_json_string, py::arg("text"),
                    "Like from_json, from a JSON string.")
        .def(
            "to_json",
            [](const Atmosphere& a, const std::filesystem::path& path, bool overwrite) {
                a.to_json_file(path.string(), overwrite);
            },
            py::arg("path"), py::arg("overwrite") = false, R"doc(
Writes the atmosphere as JSON in its explicit form (every field; reading it back
gives the same atmosphere exactly). Refuses to replace an existing file unless
overwrite=True (OSError); OSError too if the path cannot be written, or names a
directory or special file (a symlink is written through). Validates
first (ValueError).
)doc")
        .def("to_json_string", &Atmosphere::to_json_string, "The JSON text to_json writes.")
        .def(
            "aerosol_optical_depth",
            [](const Atmosphere& a, double wavelength_nm) { return aerosol_optical_depth(a, wavelength_nm); },
            py::arg("wavelength_nm") = 550.0, R"doc(
The aerosol's vertical optical depth at a wavelength (default 550 nm), from the
ground to the top (include/welkin/atmosphere/aerosol.hpp).
)doc")
        .def(
            "set_aerosol_optical_depth",
            [](Atmosphere& a, double tau_550) { set_aerosol_optical_depth(a, tau_550); }, py::arg("tau_550"),
            R"doc(
Scales the aerosol's scattering and extinction alike so that its vertical
optical depth at 550 nm is tau_550, in [0, 10] (ValueError naming
aerosol_optical_depth otherwise).
)doc")
        .def("validate", &Atmosphere::validate,
             "Raises ValueError naming the first invalid field and its accepted range.")
        .def_readwrite("name", &Atmosphere::name)
        .def_property_readonly("channels", &Atmosphere::channels,
                               "Number of wavelengths (len(wavelengths_nm)).");

    spectrum_property(atmosphere, "wavelengths_nm", &Atmosphere::wavelengths_nm,
                      "Wavelengths of the spectral samples, nm.");
    spectrum_property(atmosphere, "solar_irradiance", &Atmosphere::solar_irradiance,
                      "Extraterrestrial solar spectral irradiance at normal incidence, "
                      "W m^-2 nm^-1.");
    spectrum_property(atmosphere, "rayleigh_scattering", &Atmosphere::rayleigh_scattering,
                      "Rayleigh scattering coefficient at density 1, m^-1 (no absorption).");
    spectrum_property(atmosphere, "mie_scattering", &Atmosphere::mie_scattering,
                      "Mie (aerosol) scattering coefficient at density 1, m^-1.");
    spectrum_property(atmosphere, "mie_extinction", &Atmosphere::mie_extinction,
                      "Mie extinction coefficient at density 1, m^-1 (>= mie_scattering).");
    spectrum_property(atmosphere, "absorption_extinction", &Atmosphere::absorption_extinction,
                      "Absorbing layer (ozone) extinction at density 1, m^-1.");
    spectrum_property(atmosphere, "ground_albedo", &Atmosphere::ground_albedo,
                      "Lambertian ground albedo, 0..1.");

    bind_atmosphere_geometry_and_copies(atmosphere);
    m.def("preetham_turbidity_to_aerosol_optical_depth", &preetham_turbidity_to_aerosol_optical_depth,
          py::arg("turbidity"), R"doc(
The aerosol optical depth at 550 nm of Preetham, Shirley & Smits 1999's
turbidity T in [1, 20]: (0.04608 T - 0.04586) 0.55^-1.3 (T 2: 0.10).
ValueError naming turbidity outside the range.
)doc");
}

}  // namespace welkin::python
