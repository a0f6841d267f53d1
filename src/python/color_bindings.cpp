// SPDX-License-Identifier: Apache-2.0
// Conversions at the module's edges: spectra to RGB (color.hpp), the spectral-mode
// wavelengths (atmosphere.hpp) and Blender's equirectangular mapping (equirect.hpp),
// vectorised over numpy arrays.
#include "bindings.hpp"
#include <fmt/format.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/equirect.hpp"
#include "welkin/base/error.hpp"
#include "welkin/color/color.hpp"
#include "welkin/color/reflectance.hpp"
#include "welkin/sky/method.hpp"

namespace welkin::python {
namespace {

// The shape of `a`, (N, k) or (k,), with its last axis replaced by `last`.
std::vector<py::ssize_t> with_last_axis(const py::array& a, py::ssize_t last) {
    std::vector<py::ssize_t> shape(a.shape(), a.shape() + a.ndim());
    shape.back() = last;
    return shape;
}

py::array_t<float> spectrum_to_rgb(const py::object& spectra, const py::object& wavelengths_nm,
                                   double lambda_power, const std::string& color_space) {
    const std::vector<double> wavelengths = to_vector(wavelengths_nm, "wavelengths_nm");
    const SpectrumToRgb to_rgb(wavelengths, lambda_power, color_space_from_name(color_space));
    const auto channels = static_cast<py::ssize_t>(wavelengths.size());
    const c_array<float> in =
        to_c_array<float>(spectra, "spectra", channels, 1, 2,
                          fmt::format("an (N, C) or (C,) array with C = len(wavelengths_nm) = {}", channels));
    py::array_t<float> out(with_last_axis(in, 3));
    const std::size_t rows = static_cast<std::size_t>(in.size() / channels);
    {
        py::gil_scoped_release release;
        to_rgb.convert({in.data(), rows * channels}, {out.mutable_data(), rows * 3});
    }
    return out;
}

py::array_t<double> direction_to_equirect(const py::object& view_directions) {
    const c_array<double> in =
        to_c_array<double>(view_directions, "view_directions", 3, 1, 2, "an (N, 3) or (3,) array");
    std::vector<glm::dvec3> storage;
    // The core's check (finite, non-zero); the mapping itself needs no unit length.
    const std::span<const glm::dvec3> dirs = as_dvec3_span(in, storage);
    welkin::validate_directions(dirs);
    const std::size_t n = dirs.size();
    py::array_t<double> out(with_last_axis(in, 2));
    double* uv = out.mutable_data();
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec2 p = welkin::direction_to_equirect(dirs[i]);
        uv[2 * i] = p.x;
        uv[2 * i + 1] = p.y;
    }
    return out;
}

py::array_t<double> equirect_to_direction(const py::object& uv) {
    const c_array<double> in = to_c_array<double>(uv, "uv", 2, 1, 2, "an (N, 2) or (2,) array");
    const std::size_t n = static_cast<std::size_t>(in.size() / 2);
    const double* p = in.data();
    py::array_t<double> out(with_last_axis(in, 3));
    double* d = out.mutable_data();
    for (std::size_t i = 0; i < n; ++i) {
        require_finite(fmt::format("uv[{}][0]", i), p[2 * i]);
        require_finite(fmt::format("uv[{}][1]", i), p[2 * i + 1]);
        const glm::dvec3 v = welkin::equirect_to_direction({p[2 * i], p[2 * i + 1]});
        d[3 * i] = v.x;
        d[3 * i + 1] = v.y;
        d[3 * i + 2] = v.z;
    }
    return out;
}

py::array_t<double> equirect_pixel_directions(int width, int height) {
    require_in_range("width", width, 1, 1 << 16, "pixels");
    require_in_range("height", height, 1, 1 << 16, "pixels");
    py::array_t<double> out({py::ssize_t(height), py::ssize_t(width), py::ssize_t(3)});
    double* d = out.mutable_data();
    {
        py::gil_scoped_release release;
        for (int j = 0; j < height; ++j)
            for (int i = 0; i < width; ++i) {
                const glm::dvec3 v = equirect_pixel_direction(i, j, width, height);
                double* px = d + 3 * (std::size_t(j) * width + i);
                px[0] = v.x;
                px[1] = v.y;
                px[2] = v.z;
            }
    }
    return out;
}

}  // namespace

void register_color(py::module_& m) {
    m.def("spectrum_to_rgb", &spectrum_to_rgb, py::arg("spectra"), py::arg("wavelengths_nm"),
          py::arg("lambda_power") = -3.0, py::kw_only(), py::arg("color_space") = "rec709", R"doc(
Spectral radiance (W m^-2 sr^-1 nm^-1) at wavelengths_nm -> linear RGB of
color_space, "rec709" (default), "rec2020" or "acescg" (W m^-2 sr^-1; CIE 1931
2-degree XYZ through the space's matrix, color_space.hpp: D65 white, ACEScg's
ACES white reached by the Bradford adaptation; no 683 lm/W factor, no gamma).

spectra: (N, C) or (C,) array-like with C = len(wavelengths_nm) >= 3; returns
float32 (N, 3) or (3,). The default four wavelengths (620/560/480/440 nm) use
matrices fitted to the 48-wavelength path (lambda_power -3: sky light, 0:
sunlight); other sets of more than three wavelengths are integrated against the
colour-matching functions; with exactly three, each sample is extended as the
solar spectrum times (lambda / lambda_j)^lambda_power (Bruneton 2017's
approximate conversion): -3 for sky light, 0 for sunlight. A colour outside
Rec.709's gamut is then desaturated toward white at constant luminance until no
channel is negative (include/welkin/color/gamut.hpp). This is the conversion
sky_radiance(output="rgb") uses.
)doc");

    m.def(
        "color_space_matrix",
        [](const std::string& from, const std::string& to) {
            const Matrix3 m3 =
                from == "xyz" ? xyz_to_rgb_matrix(color_space_from_name(to))
                              : rgb_to_rgb_matrix(color_space_from_name(from), color_space_from_name(to));
            std::vector<double> flat;
            for (const auto& row : m3) flat.insert(flat.end(), row.begin(), row.end());
            py::array_t<double> a = to_readonly_array(flat);
            return a.attr("reshape")(3, 3);
        },
        py::arg("from_space"), py::arg("to_space"), R"doc(
The 3 x 3 matrix taking linear RGB of from_space to linear RGB of to_space
(rgb_to = M @ rgb_from), both "rec709", "rec2020" or "acescg"; from_space
"xyz": the CIE XYZ (D65-referred) -> to_space matrix every spectrum goes
through (color_space.hpp). Raises ValueError naming color_space otherwise.
)doc");

    m.def(
        "rgb_to_reflectance",
        [](const py::object& rgb, const py::object& wavelengths_nm, const std::string& color_space) {
            const std::vector<double> c = to_vector(rgb, "ground_color");
            if (c.size() != 3)
                throw InvalidArgument("ground_color",
                                      fmt::format("needs 3 channels (r, g, b), got {}", c.size()));
            const std::vector<double> wavelengths = to_vector(wavelengths_nm, "wavelengths_nm");
            return to_readonly_array(
                rgb_to_reflectance({c[0], c[1], c[2]}, wavelengths, color_space_from_name(color_space)));
        },
        py::arg("rgb"), py::arg("wavelengths_nm"), py::kw_only(), py::arg("color_space") = "rec709", R"doc(
The reflectance spectrum (every value in [0, 1]) at wavelengths_nm whose colour
is the linear `rgb` of color_space (each channel in [0, 1]): Jakob & Hanika
2019's sigmoid of a quadratic, fitted so that light reflected from it, relative
to a perfect white reflector, has that RGB (include/welkin/color/reflectance.hpp).
A grey is the flat spectrum of its value. Use it as Atmosphere.ground_albedo
for a ground of a chosen colour. Raises ValueError naming ground_color for a
channel outside [0, 1].
)doc");

    m.def(
        "reflectance_to_rgb",
        [](const py::object& reflectance, const py::object& wavelengths_nm, const std::string& color_space) {
            const std::vector<double> r = to_vector(reflectance, "reflectance");
            const std::vector<double> wavelengths = to_vector(wavelengths_nm, "wavelengths_nm");
            const std::array<double, 3> rgb =
                reflectance_to_rgb(r, wavelengths, color_space_from_name(color_space));
            return to_readonly_array(std::vector<double>(rgb.begin(), rgb.end()));
        },
        py::arg("reflectance"), py::arg("wavelengths_nm"), py::kw_only(), py::arg("color_space") = "rec709",
        R"doc(
The colour of a reflectance spectrum sampled at wavelengths_nm (linear in
between, constant beyond): the linear RGB of color_space of light reflected
from it relative to a perfect white reflector; rgb_to_reflectance's inverse.
)doc");

    m.def(
        "spectral_wavelengths_nm",
        [](double step_nm) { return to_readonly_array(spectral_wavelengths_nm(step_nm)); },
        py::arg("step_nm") = 10.0, R"doc(
Evenly spaced wavelengths for the spectral mode, 360..830 nm (48 samples at the
default 10 nm step): pass them to Atmosphere.preset(name, wavelengths_nm=...).
)doc");

    m.def("direction_to_equirect", &direction_to_equirect, py::arg("view_directions"), R"doc(
Blender's Environment Texture mapping, direction -> (u, v):
    u = -atan2(y, x) / (2 pi) + 1/2,   v = atan2(z, hypot(x, y)) / pi + 1/2
view_directions: (N, 3) or (3,), Z up, any non-zero length. u in [0, 1) left to
right, v in [0, 1] bottom to top (v = 1 is the zenith). Returns float64 (N, 2)
or (2,). Raises ValueError for a zero or non-finite direction.
)doc");

    m.def("equirect_to_direction", &equirect_to_direction, py::arg("uv"), R"doc(
Inverse of direction_to_equirect: (N, 2) or (2,) texture coordinates (u, v) ->
unit directions, float64 (N, 3) or (3,), Z up.
)doc");

    m.def("equirect_pixel_directions", &equirect_pixel_directions, py::arg("width"), py::arg("height"), R"doc(
Unit directions through the pixel centres of a width x height equirectangular
image stored top row first (row 0 is the zenith side, as in EXR files):
float64 array (height, width, 3). Reshape to (-1, 3) for sky_radiance.
)doc");
}

}  // namespace welkin::python
