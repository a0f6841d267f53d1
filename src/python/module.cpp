// SPDX-License-Identifier: Apache-2.0
// The `welkin` Python module: the module object, its error mapping and the small helpers
// the other bindings files share. Each part of the API registers itself from its own file:
//   atmosphere_bindings.cpp  welkin.Atmosphere, DensityProfile, DensityLayer
//   sky_bindings.cpp         welkin.sky_radiance, methods (cancellable, GIL released)
//   sun_bindings.cpp         welkin.sun
//   color_bindings.cpp       spectrum_to_rgb, spectral_wavelengths_nm, equirect mapping
//   image_bindings.cpp       sky_image, sun_disc_image (equirect sky images)
//   exr_bindings.cpp         write_exr, read_exr
//   aerial_bindings.cpp      welkin.SceneDescription, aerial_perspective
//   cloud_bindings.cpp       welkin.CloudLayer, VdbClouds, cloud_radiance
//   cloud_shadow_bindings.cpp cloud_transmittance (towards the sun, many points)
//   plate_bindings.cpp       camera_plate, CameraPlateRenderer
//   cancellable.cpp          running the core off the Python thread (Ctrl-C, progress)
#include <cstdint>
#include <cstring>
#include <sstream>

#include "bindings.hpp"
#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/scene/scene.hpp"

#ifndef WELKIN_VERSION
#define WELKIN_VERSION "unknown"
#endif

namespace welkin::python {

std::vector<double> to_vector(const py::handle& values, const std::string& parameter) {
    if (values.is_none()) return {};
    const c_array<double> array = to_c_array<double>(values, parameter, -1, 1, 1, "a sequence of numbers");
    return std::vector<double>(array.data(), array.data() + array.size());
}

py::array_t<double> to_readonly_array(const std::vector<double>& values) {
    py::array_t<double> array(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), array.mutable_data());
    array.attr("flags").attr("writeable") = false;
    return array;
}

std::string shape_string(const py::array& array) {
    std::ostringstream s;
    s << '(';
    for (py::ssize_t i = 0; i < array.ndim(); ++i) s << (i ? ", " : "") << array.shape(i);
    s << (array.ndim() == 1 ? ",)" : ")");
    return s.str();
}

py::array_t<float> to_array(std::vector<float>&& values, const std::vector<py::ssize_t>& shape) {
    auto* owner = new std::vector<float>(std::move(values));
    py::capsule free_when_done(owner, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>(shape, owner->data(), free_when_done);
}

py::array_t<float> to_image_array(std::vector<float>&& pixels, int width, int height, std::size_t channels) {
    return to_array(std::move(pixels), {py::ssize_t(height), py::ssize_t(width), py::ssize_t(channels)});
}

static_assert(sizeof(glm::dvec3) == 3 * sizeof(double),
              "a (..., 3) float64 buffer is read as glm::dvec3 in place");

std::span<const glm::dvec3> as_dvec3_span(const c_array<double>& array, std::vector<glm::dvec3>& storage) {
    const auto n = static_cast<std::size_t>(array.size() / 3);
    if (reinterpret_cast<std::uintptr_t>(array.data()) % alignof(glm::dvec3) == 0)
        return {reinterpret_cast<const glm::dvec3*>(array.data()), n};
    storage.resize(n);
    std::memcpy(storage.data(), array.data(), n * sizeof(glm::dvec3));
    return storage;
}

glm::dvec3 to_dvec3(const py::handle& values, const std::string& parameter) {
    const c_array<double> v =
        to_c_array<double>(values, parameter, 3, 1, 1, "a sequence of 3 numbers (x, y, z), Z up");
    return {v.data()[0], v.data()[1], v.data()[2]};
}

SceneDescription to_scene(const py::handle& scene) {
    if (py::isinstance<SceneDescription>(scene)) return scene.cast<SceneDescription>();
    if (py::isinstance<py::str>(scene)) return SceneDescription::from_json_string(scene.cast<std::string>());
    throw InvalidArgument("scene", "must be a welkin.SceneDescription or its JSON text");
}

void require_progress_callback(const py::object& progress) {
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
        throw py::type_error("progress: must be a callable taking the fraction done, or None");
}

void throw_bad_shape(const std::string& parameter, const std::string& expected, const std::string& got) {
    throw InvalidArgument(parameter, fmt::format("must be {}, got {}", expected, got));
}

void raise_if_out_of_memory(const py::handle& values, const py::dtype& dtype) {
    try {
        (void)py::module_::import("numpy").attr("asarray")(values, dtype);
    } catch (py::error_already_set& e) {
        if (e.matches(PyExc_MemoryError)) throw;
    }
}

namespace {

// The one place where core errors become Python exceptions: running out of memory
// (std::bad_alloc, OutOfMemory, or a MemoryLimit found before allocating) is MemoryError;
// pybind11's own translation handles the rest (other std::exception -> RuntimeError).
void translate_errors(std::exception_ptr error) {
    try {
        if (error) std::rethrow_exception(error);
    } catch (const MemoryLimit& e) {
        PyErr_SetString(PyExc_MemoryError, e.what());
    } catch (const std::bad_alloc& e) {
        // OutOfMemory names what needed the memory; a bare bad_alloc says only that.
        PyErr_SetString(PyExc_MemoryError, dynamic_cast<const OutOfMemory*>(&e)
                                               ? e.what()
                                               : "welkin: out of memory (std::bad_alloc)");
    } catch (const InvalidArgument& e) {
        PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const IoError& e) {
        PyErr_SetString(PyExc_OSError, e.what());
    } catch (const Cancelled&) {
        PyErr_SetString(PyExc_KeyboardInterrupt, "welkin: computation cancelled");
    }
}

}  // namespace
}  // namespace welkin::python

PYBIND11_MODULE(welkin, m) {
    namespace py = pybind11;
    using namespace welkin::python;

    // pybind11 before 2.12 reads NumPy 2's array descriptors wrongly (every row of an array
    // comes out as its first): a module built against such a pybind11 (Debian 12's 2.10,
    // scripts/build.sh, for /usr/bin/python3 and its NumPy 1.24) refuses a NumPy 2 at import
    // instead of returning wrong radiance. The wheel is built with a newer pybind11.
#if PYBIND11_VERSION_MAJOR == 2 && PYBIND11_VERSION_MINOR < 12
    {
        const std::string numpy_version = py::str(py::module_::import("numpy").attr("__version__"));
        if (!numpy_version.empty() && numpy_version[0] != '1' && numpy_version[1] == '.')
            throw py::import_error("welkin: this build of the module (pybind11 " PYBIND11_TOSTRING(PYBIND11_VERSION_MAJOR) "." PYBIND11_TOSTRING(PYBIND11_VERSION_MINOR) ") reads NumPy 1.x arrays only, and NumPy " +
                                   numpy_version +
                                   " is loaded; use the Python it was built for (/usr/bin/python3) or pip install the "
                                   "wheel (scripts/build_wheel.sh)");
    }
#endif

    m.doc() = R"doc(Welkin: a physically based sky and atmosphere engine (C++ core).

Conventions (the same in the core, the CLI and the Blender add-on):
  * SI units: lengths in metres, coefficients in m^-1, angles in radians
    (degrees only where a name ends in _deg).
  * Frame: Blender's world frame, Z up. The observer stands on the Z axis at
    altitude_m above a spherical ground; the planet centre is straight below.
  * sun_direction: the unit vector towards the sun.
  * Spectral radiance in W m^-2 sr^-1 nm^-1 at Atmosphere.wavelengths_nm
    (default 620, 560, 480, 440 nm); RGB is linear Rec.709 in W m^-2 sr^-1
    (CIE 1931 weighted, without the 683 lm/W factor).

Errors: bad input raises ValueError naming the parameter; file errors raise
OSError; running out of memory (or a request larger than this machine's memory)
raises MemoryError; a cancelled computation (Ctrl-C, or a progress callback returning
False) raises KeyboardInterrupt.

Quick start:
    import numpy as np, welkin
    atm = welkin.Atmosphere.preset("bruneton2017")
    dirs = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.1]])
    L = welkin.sky_radiance(atm, altitude_m=0.0, sun_direction=(0.0, 0.6, 0.8),
                            view_directions=dirs, method="lut", output="rgb")
)doc";
    m.attr("__version__") = WELKIN_VERSION;

    py::register_exception_translator(&translate_errors);

    register_atmosphere(m);
    register_sky(m);
    register_sun(m);
    register_color(m);
    register_clouds(m);  // before register_image: sky_image takes clouds=
    register_image(m);
    register_exr(m);
    register_aerial(m);
    register_plate(m);
    register_scene_sky(m);
    register_cloud_passes(m);
    register_cloud_shadow(m);
    register_astro(m);
}
