// SPDX-License-Identifier: Apache-2.0
// Internal to the Python module: each bindings file registers one part of the `welkin`
// module, and shares the few conversions they all need.
//
// The bindings own no physics. They turn Python objects into the core's types (with the
// parameter's name in every error), release the GIL, call the core, and hand the core's
// numbers back as numpy arrays. Errors travel as welkin::InvalidArgument / IoError /
// Cancelled and become ValueError / OSError / KeyboardInterrupt in one place (module.cpp).
#pragma once

#include <functional>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "welkin/base/progress.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/night/stars.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {

namespace py = pybind11;

void register_atmosphere(py::module_& m);
void register_sky(py::module_& m);
void register_sun(py::module_& m);
void register_color(py::module_& m);
void register_image(py::module_& m);
void register_exr(py::module_& m);
void register_aerial(py::module_& m);
void register_clouds(py::module_& m);
void register_plate(py::module_& m);
void register_scene_sky(py::module_& m);
void register_cloud_passes(py::module_& m);
void register_cloud_shadow(py::module_& m);
void register_astro(py::module_& m);

// An (N, 5) array of stars (x, y, z, V, B-V per row, as welkin.stars_at returns them);
// InvalidArgument naming `stars` for another shape (astro_bindings.cpp).
std::vector<Star> to_stars(const py::array_t<double>& stars);

// The night glow's options for a moment and a place (time: an ISO 8601 str or an aware
// datetime; None: no moment, the zodiacal light at its darkest everywhere), the ecliptic
// given in an image frame turned by north_deg about z from east-north-up, as a host turns
// stars_at's directions; InvalidArgument naming time or north_deg (astro_bindings.cpp).
// Holding the GIL; the moment is parsed here.
NightGlowOptions night_glow_options(const py::object& time, double latitude_deg, double longitude_deg,
                                    double height_m, double north_deg, bool airglow = true,
                                    bool zodiacal_light = true);

// Any 1-D array-like of numbers -> std::vector<double>; InvalidArgument(parameter) if it
// is not one.
std::vector<double> to_vector(const py::handle& values, const std::string& parameter);

// A float64 array of shape (n,), a copy of `values`, read-only so that in-place edits
// (atm.mie_scattering[0] = ..) fail loudly instead of changing a temporary.
py::array_t<double> to_readonly_array(const std::vector<double>& values);

// Any array-like -> C-contiguous array of T (no copy when it already is one); the shape
// must be (..., last_dim) (any last axis when last_dim < 0) with `min_ndim` (>= 1) to
// `max_ndim` axes, else InvalidArgument naming `parameter` and the shape it got.
template <class T>
using c_array = py::array_t<T, py::array::c_style | py::array::forcecast>;

std::string shape_string(const py::array& array);

[[noreturn]] void throw_bad_shape(const std::string& parameter, const std::string& expected,
                                  const std::string& got);

// After a conversion of `values` to an array of `dtype` failed (pybind11's ensure() hides
// why): raises Python's MemoryError when that was the reason (numpy's message names the
// size), and returns otherwise.
void raise_if_out_of_memory(const py::handle& values, const py::dtype& dtype);

template <class T>
c_array<T> to_c_array(const py::handle& values, const std::string& parameter, py::ssize_t last_dim,
                      int min_ndim, int max_ndim, const std::string& expected) {
    // ensure() converts like numpy.ascontiguousarray(values, dtype=T): it returns the same
    // object when it already is one, and an empty handle when it cannot convert.
    c_array<T> array = c_array<T>::ensure(values);
    if (!array) {
        raise_if_out_of_memory(values, py::dtype::of<T>());
        throw_bad_shape(parameter, expected, "something that is not an array of numbers");
    }
    if (array.ndim() < min_ndim || array.ndim() > max_ndim ||
        (last_dim >= 0 && array.shape(array.ndim() - 1) != last_dim))
        throw_bad_shape(parameter, expected, "shape " + shape_string(array));
    return array;
}

// The (..., 3) float64 array's buffer as directions, in place (no copy) when it is aligned
// as numpy's own allocations are; else copied into `storage`.
std::span<const glm::dvec3> as_dvec3_span(const c_array<double>& array, std::vector<glm::dvec3>& storage);

// A float32 array of `shape` (C order) that owns `values` (moved, not copied).
py::array_t<float> to_array(std::vector<float>&& values, const std::vector<py::ssize_t>& shape);
// A (height, width, channels) float32 array that owns `pixels` (moved, not copied).
py::array_t<float> to_image_array(std::vector<float>&& pixels, int width, int height, std::size_t channels);

// "rgb" | "spectral" -> the sky image's output (InvalidArgument naming "output").
SkyImageOptions::Output parse_output(const std::string& output);

// A sequence of three numbers -> glm::dvec3 (InvalidArgument naming `parameter` otherwise).
glm::dvec3 to_dvec3(const py::handle& values, const std::string& parameter);

// The `scene` argument of the scene calls: a welkin.SceneDescription, or its JSON text
// (parsed; the core's InvalidArgument names the key). Else InvalidArgument "scene".
SceneDescription to_scene(const py::handle& scene);

// The `progress` argument of the long calls: None, or a callable taking the fraction done
// (py::type_error otherwise), passed to run_cancellable.
void require_progress_callback(const py::object& progress);

// Runs `work` (which calls the core, and must not touch Python) on a worker thread with
// the GIL released, while this thread keeps Python responsive: it checks for Ctrl-C
// (PyErr_CheckSignals only sees signals on Python's main thread, which is why the core
// does not run here) and calls `callback(fraction)` with the core's progress, unless it
// is None. Ctrl-C, or the callback returning False, cancels: the core stops at its next
// progress check. Raises, in this order of precedence, the Python exception that stopped
// it (KeyboardInterrupt for Ctrl-C, or whatever the callback raised), else the core's
// exception (welkin::Cancelled when the callback returned False).
void run_cancellable(const std::function<void(Progress*)>& work, const py::object& callback);

}  // namespace welkin::python
