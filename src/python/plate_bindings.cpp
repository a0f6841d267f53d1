// SPDX-License-Identifier: Apache-2.0
// welkin.camera_plate: the scene camera's plate (camera_plate.hpp) as numpy arrays.
#include <memory>
#include <optional>
#include <utility>

#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/base/row_range.hpp"
#include "welkin/render/camera_plate.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {
namespace {

constexpr const char* kPlateDoc = R"doc(
The scene camera's plate: sky with the sun's disc, and a black ground seen through the air
(aerial perspective), no meshes; what the Blender render engine "WELKIN" and
`welkin plate` render (camera_plate.hpp).

scene    : welkin.SceneDescription or its JSON text, with a camera
progress : callable(fraction) -> bool or None; returning False cancels
           (welkin.Cancelled / KeyboardInterrupt, nothing returned)
rows     : None (the whole frame) or (begin, end): only rows [begin, end) counted from
           the top, with the values the whole frame has there (the render engine's
           tiles); the arrays then have end - begin rows

Returns a dict of float32 arrays, top row first: "combined", "sky", "inscatter",
"transmittance" (height, width, 3) and "depth" (height, width; +inf on sky),
"clouds" (height, width, 4: Welkin.Clouds, premultiplied; alpha 0 without clouds) and
"cloud_depth" (height, width: Welkin.CloudDepth, 1e10 where no cloud), plus "method"
(the sky method that ran). Linear Rec.709, W m^-2 sr^-1, times the exposure. With
clouds, "combined" = clouds over the clear plate: clouds.rgb + (1 - clouds.a) (sky +
inscatter), the sun's disc dimmed by the clouds.
Raises ValueError naming the field: no camera ("camera"), a camera at or below the
ground ("camera.matrix_world"), a bad row range ("rows"), a cloud volume that cannot
be read ("clouds.volumes[i].file").
)doc";

constexpr const char* kRendererDoc = R"doc(
A frame's plate prepared once and rendered band by band (camera_plate.hpp, "Rows"): the
constructor does the frame-wide work (checks, cloud density, the whole frame's depth, the
sky method's choice, the aerial perspective's LUTs and froxel volume), render(rows=...)
the band's pixels, with exactly camera_plate(scene, rows=...)'s values. What the render
engine's tiles and the viewport preview use.

CameraPlateRenderer(scene): scene a welkin.SceneDescription or its JSON text; raises
ValueError as camera_plate does.
render(rows=None, progress=None): camera_plate's dict for rows (begin, end) (None: all).
width, height: the frame's pixels; method: the sky method; has_clouds.
Safe to call render() from several Python threads (the GIL is released while it runs).
)doc";

SceneDescription scene_from(const py::handle& scene_in) {
    SceneDescription scene = to_scene(scene_in);
    scene.require_camera();
    return scene;
}

py::dict plate_dict(CameraPlate&& plate) {
    const int w = plate.width, h = plate.height;
    py::dict out;
    out["combined"] = to_image_array(std::move(plate.combined), w, h, 3);
    out["sky"] = to_image_array(std::move(plate.sky), w, h, 3);
    out["inscatter"] = to_image_array(std::move(plate.inscatter), w, h, 3);
    out["transmittance"] = to_image_array(std::move(plate.transmittance), w, h, 3);
    py::array_t<float> depth({py::ssize_t(h), py::ssize_t(w)});
    std::copy(plate.depth.begin(), plate.depth.end(), depth.mutable_data());
    out["depth"] = depth;
    out["clouds"] = to_image_array(std::move(plate.clouds), w, h, 4);
    py::array_t<float> cloud_depth({py::ssize_t(h), py::ssize_t(w)});
    std::copy(plate.cloud_depth.begin(), plate.cloud_depth.end(), cloud_depth.mutable_data());
    out["cloud_depth"] = cloud_depth;
    out["method"] = plate.method;
    return out;
}

RowRange band_of(const std::optional<std::pair<int, int>>& rows, int height) {
    return rows ? RowRange{rows->first, rows->second}.resolved(height) : RowRange{};
}

py::dict camera_plate_py(const py::handle& scene_in, const py::object& progress,
                         const std::optional<std::pair<int, int>>& rows) {
    const SceneDescription scene = scene_from(scene_in);
    require_progress_callback(progress);
    const RowRange band = band_of(rows, scene.resolution.height());
    CameraPlate plate;
    run_cancellable([&](Progress* p) { plate = render_camera_plate(scene, p, band); }, progress);
    return plate_dict(std::move(plate));
}

std::shared_ptr<CameraPlateRenderer> make_renderer(const py::handle& scene_in) {
    const SceneDescription scene = scene_from(scene_in);
    std::shared_ptr<CameraPlateRenderer> renderer;
    run_cancellable([&](Progress*) { renderer = std::make_shared<CameraPlateRenderer>(scene); }, py::none());
    return renderer;
}

py::dict renderer_render(const CameraPlateRenderer& renderer, const std::optional<std::pair<int, int>>& rows,
                         const py::object& progress) {
    require_progress_callback(progress);
    const RowRange band = band_of(rows, renderer.height());
    CameraPlate plate;
    run_cancellable([&](Progress* p) { plate = renderer.render(band, p); }, progress);
    return plate_dict(std::move(plate));
}

}  // namespace

void register_plate(py::module_& m) {
    m.def("camera_plate", &camera_plate_py, kPlateDoc, py::arg("scene"), py::kw_only(),
          py::arg("progress") = py::none(), py::arg("rows") = py::none());
    py::class_<CameraPlateRenderer, std::shared_ptr<CameraPlateRenderer>>(m, "CameraPlateRenderer",
                                                                          kRendererDoc)
        .def(py::init(&make_renderer), py::arg("scene"))
        .def("render", &renderer_render, py::kw_only(), py::arg("rows") = py::none(),
             py::arg("progress") = py::none())
        .def_property_readonly("width", &CameraPlateRenderer::width)
        .def_property_readonly("height", &CameraPlateRenderer::height)
        .def_property_readonly("method", &CameraPlateRenderer::method)
        .def_property_readonly("has_clouds", &CameraPlateRenderer::has_clouds);
}

}  // namespace welkin::python
