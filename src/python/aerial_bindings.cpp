// SPDX-License-Identifier: Apache-2.0
// welkin.SceneDescription and welkin.aerial_perspective (include/welkin/scene/scene.hpp,
// aerial_perspective.hpp): what the Blender add-on needs to turn a rendered frame's depth
// into its aerial-perspective passes (EXR files in and out: exr_bindings.cpp). Thin: the
// scene travels as its JSON text, the depth as a numpy array, the passes come back as
// numpy arrays the core wrote into.
#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/aerial/aerial_table.hpp"
#include "welkin/atmosphere/lut_cache.hpp"
#include "welkin/base/camera.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/memory.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {
namespace {

const char* const kAerialDoc = R"doc(
Aerial-perspective passes of a rendered frame.

    inscatter, transmittance = welkin.aerial_perspective(scene.aerial_view(), depth, method=None)

Parameters
----------
scene : welkin.SceneDescription or str
    The frame's scene description (or its JSON text); it must have a camera. Its
    resolution (x, y, percentage) must give depth's shape.
depth : array-like, shape (height, width)
    Blender's Z pass, metres: along the view axis for perspective and orthographic
    cameras, along the ray for panoramic ones. Rows top first (as in EXR files;
    Blender's own pixel buffers are bottom row first: flip them with depth[::-1]).
    +inf or >= aerial.sky_depth_m (default 1e9; Cycles writes 1e10 for the
    background) marks sky pixels: transmittance 1, no in-scattering.
method : None, "froxel" or "raymarch"
    None: the scene's aerial.method. "froxel": Hillaire 2020's camera volume;
    "raymarch": every pixel marched to its depth (slow, the reference).
progress : callable(fraction) or None
    Called with the fraction done; return False to cancel (KeyboardInterrupt).

Returns
-------
(inscatter, transmittance), float32 arrays of shape (height, width, 3), rows top
first. inscatter: linear Rec.709, W m^-2 sr^-1, times the scene's exposure;
transmittance: dimensionless in [0, 1]. Image x transmittance + inscatter is the
hazed render (the Welkin Aerial Perspective node group does exactly that).

Raises ValueError naming the parameter (no camera, a NaN or negative depth, a
depth whose shape is not the scene's resolution, a render too large for memory).
)doc";

py::tuple aerial_perspective_py(const py::handle& scene_in, const py::handle& depth_in,
                                const py::object& method, const py::object& progress) {
    SceneDescription scene = to_scene(scene_in);
    if (!method.is_none())
        scene.aerial.method = aerial_method_from_name(method.cast<std::string>(), "method");
    require_progress_callback(progress);
    scene.require_camera();
    const int width = scene.resolution.width(), height = scene.resolution.height();
    check_frame_memory(width, height, kAerialPassBytesPerPixel + 6 * sizeof(float),  // the returned arrays
                       "depth and aerial passes (float)");
    const c_array<float> depth =
        to_c_array<float>(depth_in, "depth", -1, 2, 2, "a (height, width) array of depths in metres");
    if (depth.shape(0) != height || depth.shape(1) != width)
        throw InvalidArgument("depth",
                              fmt::format("has shape ({}, {}) but the scene renders {} x {} "
                                          "(shape ({}, {}))",
                                          depth.shape(0), depth.shape(1), width, height, height, width));
    const std::span<const float> z(depth.data(), std::size_t(depth.size()));
    AerialPasses passes;
    run_cancellable(
        [&](Progress* p) { passes = aerial_perspective(scene.aerial_view(), z, width, height, p); },
        progress);
    return py::make_tuple(to_image_array(std::move(passes.inscatter), width, height, 3),
                          to_image_array(std::move(passes.transmittance), width, height, 3));
}

const char* const kAerialTableDoc = R"doc(
Aerial perspective from the scene camera's position as a table of view direction and
distance (include/welkin/aerial/aerial_table.hpp): what a shader samples per shading
point to haze a render in the render itself.

scene : SceneDescription or its JSON text (atmosphere, origin altitude, sun, exposure and
    the camera, whose position is the viewpoint)
azimuths, elevations, slices : the table's size (azimuth over the full circle, elevation
    from nadir to zenith crowded at the horizon, distance slices
    d_k = linear_distance_m (exp(k c) - 1), c = ln(1 + max_distance_m / linear_distance_m)
    / (slices - 1), slice 0 at d = 0)
max_distance_m : the last slice's distance, m (at least 2 linear_distance_m)
linear_distance_m : below it the slices are about evenly spaced, beyond it geometric, m
steps_per_slice : march steps per slice

Returns {"inscatter", "optical_depth"}: float32 arrays (slices, elevations, azimuths, 3);
inscatter in the passes' units (linear Rec.709 W m^-2 sr^-1 times the exposure), optical
depth -ln T of the passes' transmittance. ValueError names a bad parameter.
)doc";

py::dict aerial_table_py(const py::handle& scene_in, int azimuths, int elevations, int slices,
                         double max_distance_m, double linear_distance_m, int steps_per_slice,
                         const py::object& progress) {
    const SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    const AerialView view = scene.aerial_view();
    AerialTableLayout layout;
    layout.azimuths = azimuths;
    layout.elevations = elevations;
    layout.slices = slices;
    layout.max_distance_m = max_distance_m;
    layout.linear_distance_m = linear_distance_m;
    layout.steps_per_slice = steps_per_slice;
    layout.validate("");
    AerialTable table;
    run_cancellable(
        [&](Progress* p) {
            const auto luts = AtmosphereLutCache::shared().get(view.atmosphere, view.luts);
            table = aerial_table(view.atmosphere, *luts, view.planet_centre(),
                                 CameraRays(view.camera, view.width, view.height).position(),
                                 view.origin.sun_direction, view.exposure, layout, p, view.color_space);
        },
        progress);
    const std::vector<py::ssize_t> shape{slices, elevations, azimuths, 3};
    py::dict out;
    out["inscatter"] = to_array(std::move(table.inscatter), shape);
    out["optical_depth"] = to_array(std::move(table.optical_depth), shape);
    return out;
}

const char* const kAerialScreenTableDoc = R"doc(
Aerial perspective of the scene camera as a table over its screen and the distance
(include/welkin/aerial/aerial_table.hpp): what a shader that knows a shading point's place
in the frame and its distance samples to haze a render in the render itself.

scene : SceneDescription or its JSON text (atmosphere, origin altitude, sun, exposure, the
    camera with its clip range, and the render resolution)
coordinate : "window" (Blender's Texture Coordinate > Window) or "view_vector" (Camera
    Data > View Vector; perspective cameras only): what the lattice is laid over
columns, rows : lattice points across the frame widened by margin_x, margin_y (Window
    fractions beyond each edge)
unit_m : the shader's distance unit in metres (Blender's unit scale)
ratio, max_slices : distance slices at integer powers of ratio (in that unit) from below
    the clip start to beyond the farthest distance seen; the ratio grows to keep to
    max_slices
steps_per_slice : march steps per slice

Returns {"inscatter", "transmittance", "textures", "lattice"}: float32 arrays (slices,
rows, columns, 3), lattice row 0 (the lowest) first, inscatter in the passes' units (linear
Rec.709 W m^-2 sr^-1 times the exposure); (3, slices x rows, columns, 4), the three RGBA
textures a shader reads (AerialScreenTable::textures; rows bottom first); and the lattice:
{"coordinate", "columns", "rows", "slices", "spacing_x", "spacing_y", "first_x",
"first_y", "ratio", "first_exponent", "unit_m"}. ValueError names a bad parameter.
)doc";

ScreenCoordinate screen_coordinate_from_name(const std::string& name) {
    if (name == "window") return ScreenCoordinate::Window;
    if (name == "view_vector") return ScreenCoordinate::ViewVector;
    throw InvalidArgument("coordinate",
                          fmt::format("must be \"window\" or \"view_vector\", got \"{}\"", name));
}

py::dict aerial_screen_table_py(const py::handle& scene_in, const AerialScreenTableLayout& layout,
                                const py::object& progress) {
    const SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    const AerialView view = scene.aerial_view();
    layout.validate("");
    AerialScreenTable table;
    run_cancellable(
        [&](Progress* p) {
            const auto luts = AtmosphereLutCache::shared().get(view.atmosphere, view.luts);
            table = aerial_screen_table(view, *luts, layout, p);
        },
        progress);
    const AerialScreenLattice& g = table.lattice;
    py::array_t<float> tex(
        {py::ssize_t(3), py::ssize_t(g.slices) * g.rows, py::ssize_t(g.columns), py::ssize_t(4)});
    table.textures({tex.mutable_data(), table.texture_floats()});
    const std::vector<py::ssize_t> shape{g.slices, g.rows, g.columns, 3};
    py::array_t<float> L = to_array(std::move(table.inscatter), shape);
    py::array_t<float> T = to_array(std::move(table.transmittance), shape);
    py::dict lattice;
    lattice["coordinate"] = g.coordinate == ScreenCoordinate::ViewVector ? "view_vector" : "window";
    lattice["columns"] = g.columns;
    lattice["rows"] = g.rows;
    lattice["slices"] = g.slices;
    lattice["spacing_x"] = g.spacing_x;
    lattice["spacing_y"] = g.spacing_y;
    lattice["first_x"] = g.first_x;
    lattice["first_y"] = g.first_y;
    lattice["ratio"] = g.ratio;
    lattice["first_exponent"] = g.first_exponent;
    lattice["unit_m"] = g.unit_m;
    py::dict out;
    out["inscatter"] = L;
    out["transmittance"] = T;
    out["textures"] = tex;
    out["lattice"] = lattice;
    return out;
}

}  // namespace

void register_aerial(py::module_& m) {
    py::class_<SceneDescription>(m, "SceneDescription", R"doc(
A frame's scene description: atmosphere, sun, scene origin altitude, exposure, sky
method, Blender camera, render resolution and aerial options (docs/pipelines.md "Scene JSON").
Plain data: build it from JSON, write it back; to_json_string() reproduces the
frame exactly (the atmosphere is written in full).
)doc")
        .def_static("from_json_string", &SceneDescription::from_json_string, py::arg("text"),
                    py::arg("base_directory") = "",
                    "Parse and validate; ValueError names the key (e.g. camera.lens_mm). Relative "
                    "clouds.volumes[i].file paths are resolved against base_directory (default: "
                    "the working directory); from_json resolves them against the file's folder.")
        .def_static("from_json", &SceneDescription::from_json_file, py::arg("path"))
        .def("to_json_string", &SceneDescription::to_json_string)
        .def("to_json", &SceneDescription::to_json_file, py::arg("path"), py::arg("overwrite") = false,
             "Write atomically; refuses to replace a file unless overwrite=True.")
        .def_property_readonly(
            "width", [](const SceneDescription& s) { return s.resolution.width(); },
            "Rendered width in pixels (resolution x times percentage / 100).")
        .def_property_readonly("height", [](const SceneDescription& s) { return s.resolution.height(); })
        .def_property_readonly("has_camera", [](const SceneDescription& s) { return bool(s.camera); })
        .def_property_readonly("version", [](const SceneDescription& s) { return s.version; })
        .def_property_readonly("has_clouds", &SceneDescription::has_clouds,
                               "True when the scene's \"clouds\" hold a layer or a volume.")
        .def(
            "camera_ray",
            [](const SceneDescription& s, double sx, double sy) {
                const CameraRays rays(s.require_camera(), s.resolution.width(), s.resolution.height());
                const CameraRays::Ray r = rays.at_screen(sx, sy);
                return py::make_tuple(py::make_tuple(r.origin.x, r.origin.y, r.origin.z),
                                      py::make_tuple(r.direction.x, r.direction.y, r.direction.z),
                                      r.distance_per_depth);
            },
            py::arg("sx"), py::arg("sy"), R"doc(
The camera's ray at screen coordinates (sx, sy) in [0, 1], left to right and top to
bottom (pixel (i, j)'s centre is ((i + 0.5) / width, (j + 0.5) / height)):
(origin, unit direction, distance_per_depth), world frame, metres; a surface at Z-pass
depth z lies z * distance_per_depth along the ray. ValueError without a camera.
)doc")
        .def("__repr__", [](const SceneDescription& s) {
            return fmt::format("<welkin.SceneDescription {} x {}, atmosphere '{}', camera {}>",
                               s.resolution.width(), s.resolution.height(), s.atmosphere.name,
                               s.camera ? camera_type_name(s.camera->type) : "none");
        });

    m.def("aerial_perspective", &aerial_perspective_py, kAerialDoc, py::arg("scene"), py::arg("depth"),
          py::arg("method") = py::none(), py::kw_only(), py::arg("progress") = py::none());
    m.def("aerial_table", &aerial_table_py, kAerialTableDoc, py::arg("scene"), py::kw_only(),
          py::arg("azimuths") = 128, py::arg("elevations") = 64, py::arg("slices") = 48,
          py::arg("max_distance_m"), py::arg("linear_distance_m") = 100.0, py::arg("steps_per_slice") = 4,
          py::arg("progress") = py::none());
    m.def(
        "aerial_screen_table",
        [](const py::handle& scene, const std::string& coordinate, int columns, int rows, double margin_x,
           double margin_y, double unit_m, double ratio, int max_slices, int steps_per_slice,
           const py::object& progress) {
            AerialScreenTableLayout layout;
            layout.coordinate = screen_coordinate_from_name(coordinate);
            layout.columns = columns;
            layout.rows = rows;
            layout.margin_x = margin_x;
            layout.margin_y = margin_y;
            layout.unit_m = unit_m;
            layout.ratio = ratio;
            layout.max_slices = max_slices;
            layout.steps_per_slice = steps_per_slice;
            return aerial_screen_table_py(scene, layout, progress);
        },
        kAerialScreenTableDoc, py::arg("scene"), py::kw_only(), py::arg("coordinate") = "window",
        py::arg("columns") = 32, py::arg("rows") = 48, py::arg("margin_x") = 0.02, py::arg("margin_y") = 0.02,
        py::arg("unit_m") = 1.0, py::arg("ratio") = 1.15, py::arg("max_slices") = 256,
        py::arg("steps_per_slice") = 1, py::arg("progress") = py::none());
}

}  // namespace welkin::python
