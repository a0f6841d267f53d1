// SPDX-License-Identifier: Apache-2.0
// welkin.sky_radiance and welkin.methods: the sky methods of include/welkin/sky/method.hpp.
//
// The hot path copies nothing it does not have to: a C-contiguous float64 (N, 3) array
// reaches the core as the std::span<const glm::dvec3> it already is, and the core writes
// straight into the numpy array that is returned. Other inputs (float32, strided, lists)
// are converted once, as numpy.ascontiguousarray(dtype=float64) would.
#include <optional>

#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/color/color.hpp"
#include "welkin/sky/auto.hpp"
#include "welkin/sky/auto_table.hpp"
#include "welkin/sky/method.hpp"

namespace welkin::python {
namespace {

const char* const kSkyRadianceDoc = R"doc(
Sky (path) radiance seen by an observer, for many view directions.

    L = welkin.sky_radiance(atm, altitude_m=0.0, sun_direction=(x, y, z),
                            view_directions=dirs, method="auto", output="spectral")

Frame: Blender's world frame, Z up, metres. The observer stands on the Z axis
altitude_m metres above a spherical ground of radius atm.bottom_radius_m; the
planet centre is straight below.

Parameters
----------
atmosphere : welkin.Atmosphere
altitude_m : float
    Observer altitude above the ground, m (>= 0; may be above the atmosphere).
sun_direction : 3 numbers
    Vector towards the sun (normalised here; need not be unit length).
view_directions : array-like, shape (N, 3)
    Unit vectors from the observer towards the sky, Z up. float64 C-contiguous
    arrays are used in place; anything else is converted once.
method : str
    "analytic" | "lut" | "raymarch" | "reference" | "auto" (see welkin.methods()):
    fast approximations up to Monte-Carlo path tracing of all orders; "auto" picks,
    per scene, the cheapest of the first three that the speed-accuracy chart shows
    meeting `tolerance` (see welkin.auto_choice).
output : str
    "spectral": W m^-2 sr^-1 nm^-1 at atm.wavelengths_nm, shape (N, C).
    "rgb": linear RGB of color_space (keyword: "rec709" by default, "rec2020",
    "acescg") in W m^-2 sr^-1 (CIE 1931, without the 683 lm/W factor; 3
    wavelengths are extended as a power law, lambda^-3), shape (N, 3).

Keyword-only options (defaults are the core's, welkin::SkyOptions)
----------------------------------------------------------------
steps, sun_steps : int
    raymarch: steps along each view ray, and along each ray towards the sun.
paths : int
    reference: Monte-Carlo paths per direction (and wavelength).
seed : int
    reference: random seed; the same seed gives the same numbers everywhere.
tolerance : float
    auto: the relative luminance error to meet, as the 95th percentile over the
    sphere against the reference, in [0.001, 10] (0.1 = 10 %).
transmittance_width, transmittance_height, multiscattering_size,
skyview_width, skyview_height : int
    lut: texture sizes (Hillaire 2020's defaults).
return_standard_error : bool
    If True return (L, standard_error), both (N, C) float32: the Monte-Carlo
    standard error of each value (zeros for deterministic methods). Spectral
    output only.
progress : callable(fraction) or None
    Called on this thread with the fraction done (0..1); return False to
    cancel (KeyboardInterrupt). An exception it raises stops the computation
    and propagates.

Returns
-------
numpy.ndarray, float32, shape (N, C) or (N, 3), C-contiguous, owning its data.
"Sky radiance only": no sun disc, no ground surface at the end of the ray
(ground-reflected light scattered back by the air is included where the method
models multiple scattering). Rays that hit the ground carry the path radiance
up to the ground.

The GIL is released while the core computes; Ctrl-C cancels (KeyboardInterrupt).
Raises ValueError naming the parameter for bad input (unknown method or output,
view_directions not (N, 3), a NaN or zero-length direction, altitude_m < 0, an
invalid atmosphere or option).
)doc";

py::object sky_radiance(Atmosphere atmosphere, double altitude_m, const py::object& sun_direction,
                        const py::object& view_directions, const std::string& method,
                        const std::string& output, int steps, int sun_steps, int paths, std::uint64_t seed,
                        int transmittance_width, int transmittance_height, int multiscattering_size,
                        int skyview_width, int skyview_height, double tolerance, bool return_standard_error,
                        const py::object& progress, const std::string& color_space) {
    // The checks that need no core work come first. `atmosphere` is a copy, so that Python
    // code running while the GIL is released (other threads, the progress callback) cannot
    // change it under the core.
    if (output != "spectral" && output != "rgb")
        throw InvalidArgument("output", fmt::format("must be \"spectral\" or \"rgb\", got \"{}\"", output));
    const bool rgb = output == "rgb";
    if (rgb && return_standard_error)
        throw InvalidArgument("return_standard_error", "is only available with output=\"spectral\"");
    require_progress_callback(progress);

    SkyOptions options;
    options.raymarch_steps = steps;
    options.raymarch_sun_steps = sun_steps;
    options.reference_paths = paths;
    options.seed = seed;
    options.transmittance_width = transmittance_width;
    options.transmittance_height = transmittance_height;
    options.multiscattering_size = multiscattering_size;
    options.skyview_width = skyview_width;
    options.skyview_height = skyview_height;
    options.tolerance = tolerance;
    const std::unique_ptr<SkyMethod> sky = make_sky_method(method, options);

    const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};

    const c_array<double> dirs = to_c_array<double>(view_directions, "view_directions", 3, 2, 2,
                                                    "an (N, 3) array of unit vectors (Z up)");
    std::vector<glm::dvec3> storage;
    const std::span<const glm::dvec3> directions = as_dvec3_span(dirs, storage);
    const std::size_t n = directions.size();

    const std::size_t channels = atmosphere.channels();
    const auto rows = static_cast<py::ssize_t>(n);
    std::optional<SpectrumToRgb> to_rgb;
    if (rgb) to_rgb.emplace(atmosphere.wavelengths_nm, -3.0, color_space_from_name(color_space));

    // Spectral output goes straight into the returned array; RGB through one (N, C) buffer.
    py::array_t<float> result({rows, static_cast<py::ssize_t>(rgb ? 3 : channels)});
    std::vector<float> spectral_buffer(rgb ? n * channels : 0);
    const std::span<float> spectral =
        rgb ? std::span<float>(spectral_buffer) : std::span<float>(result.mutable_data(), n * channels);
    py::array_t<float> standard_error;
    std::span<float> standard_error_out;
    if (return_standard_error) {
        standard_error = py::array_t<float>({rows, static_cast<py::ssize_t>(channels)});
        standard_error_out = {standard_error.mutable_data(), n * channels};
    }
    const std::span<float> rgb_out =
        rgb ? std::span<float>(result.mutable_data(), n * 3) : std::span<float>();

    run_cancellable(
        [&](Progress* p) {
            sky->radiance(atmosphere, observer, directions, spectral, standard_error_out, p);
            if (to_rgb) to_rgb->convert(spectral, rgb_out);
        },
        progress);

    if (return_standard_error) return py::make_tuple(result, standard_error);
    return result;
}

}  // namespace

void register_sky(py::module_& m) {
    const SkyOptions defaults;
    m.def("sky_radiance", &sky_radiance, kSkyRadianceDoc, py::arg("atmosphere"), py::arg("altitude_m"),
          py::arg("sun_direction"), py::arg("view_directions"), py::arg("method") = "lut",
          py::arg("output") = "spectral", py::kw_only(), py::arg("steps") = defaults.raymarch_steps,
          py::arg("sun_steps") = defaults.raymarch_sun_steps, py::arg("paths") = defaults.reference_paths,
          py::arg("seed") = defaults.seed, py::arg("transmittance_width") = defaults.transmittance_width,
          py::arg("transmittance_height") = defaults.transmittance_height,
          py::arg("multiscattering_size") = defaults.multiscattering_size,
          py::arg("skyview_width") = defaults.skyview_width,
          py::arg("skyview_height") = defaults.skyview_height, py::arg("tolerance") = defaults.tolerance,
          py::arg("return_standard_error") = false, py::arg("progress") = py::none(),
          py::arg("color_space") = "rec709");

    m.def(
        "auto_choice",
        [](const Atmosphere& atmosphere, double altitude_m, const py::object& sun_direction,
           std::size_t n_directions, double tolerance) {
            const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};
            const AutoChoice c = choose_sky_method(atmosphere, observer, n_directions, tolerance);
            py::dict d;
            d["method"] = c.method;
            d["setting"] = c.setting;
            d["predicted_error"] = c.predicted_error;
            d["predicted_seconds"] = c.predicted_seconds;
            d["meets_tolerance"] = c.meets_tolerance;
            py::dict options;
            options["transmittance_width"] = c.options.transmittance_width;
            options["transmittance_height"] = c.options.transmittance_height;
            options["multiscattering_size"] = c.options.multiscattering_size;
            options["skyview_width"] = c.options.skyview_width;
            options["skyview_height"] = c.options.skyview_height;
            options["steps"] = c.options.raymarch_steps;
            options["sun_steps"] = c.options.raymarch_sun_steps;
            d["options"] = options;
            return d;
        },
        py::arg("atmosphere"), py::arg("altitude_m"), py::arg("sun_direction"), py::arg("n_directions"),
        py::arg("tolerance") = defaults.tolerance, R"doc(
What method="auto" runs for this scene: a dict with "method", "options" (keyword
arguments of sky_radiance for that method), "setting" (a label),
"predicted_error" (the chart's p95 relative luminance error, worst grid corner
around the scene), "predicted_seconds" (CPU seconds on the machine the chart ran on, for
n_directions directions) and "meets_tolerance" (False when no charted setting
meets it there and auto falls back to the most accurate one).
)doc");

    m.def(
        "chart_table",
        [] {
            const auto_table::Table& t = auto_table::table();
            py::list settings;
            for (const auto_table::Setting& s : t.settings) {
                py::dict d;
                d["method"] = s.method;
                d["spectral"] = s.spectral;
                py::dict options;
                options["transmittance_width"] = s.transmittance_width;
                options["transmittance_height"] = s.transmittance_height;
                options["multiscattering_size"] = s.multiscattering_size;
                options["skyview_width"] = s.skyview_width;
                options["skyview_height"] = s.skyview_height;
                options["steps"] = s.raymarch_steps;
                options["sun_steps"] = s.raymarch_sun_steps;
                d["options"] = options;
                d["fixed_seconds"] = s.fixed_seconds;
                d["seconds_per_direction"] = s.seconds_per_direction;
                settings.append(d);
            }
            py::dict d;
            d["altitudes_m"] = std::vector<double>(t.altitudes_m.begin(), t.altitudes_m.end());
            d["sun_elevations_deg"] =
                std::vector<double>(t.sun_elevations_deg.begin(), t.sun_elevations_deg.end());
            d["presets"] = std::vector<std::string>(t.presets.begin(), t.presets.end());
            d["settings"] = settings;
            d["reference_paths"] = t.reference_paths;
            d["reference_seconds_per_path"] = t.reference_seconds_per_path;
            return d;
        },
        R"doc(
The speed-accuracy table method="auto" chooses from (generated by bench/chart.py):
the charted grid ("altitudes_m", "sun_elevations_deg", "presets"), and per
"settings" entry its method, options and measured CPU cost ("fixed_seconds" +
"seconds_per_direction" x N on the machine the chart ran on), plus the reference's
cost ("reference_seconds_per_path" x paths x N).
)doc");

    m.def("methods", &sky_method_names, R"doc(
Names of the sky methods, fastest first: "analytic" (no marching), "lut"
(Hillaire 2020 look-up tables), "raymarch" (nested single-scattering march plus
a multiple-scattering term), "reference" (Monte-Carlo path tracing, all orders),
then "auto" (the cheapest of the first three that meets a tolerance).
)doc");
}

}  // namespace welkin::python
