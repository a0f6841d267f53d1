// welkin.camera_plate: the scene camera's plate (camera_plate.hpp) as numpy arrays.
#include <optional>
#include <utility>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "welkin/camera_plate.hpp"
#include "welkin/error.hpp"
#include "welkin/row_range.hpp"

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

py::dict camera_plate_py(const py::handle& scene_in, const py::object& progress,
                         const std::optional<std::pair<int, int>>& rows) {
    SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    scene.require_camera();
    CameraPlate plate;
    RowRange band;
    if (rows) band = RowRange{rows->first, rows->second}.resolved(scene.resolution.height());
    run_cancellable([&](Progress* p) { plate = render_camera_plate(scene, p, band); }, progress);
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

}  // namespace

void register_plate(py::module_& m) {
    m.def("camera_plate", &camera_plate_py, kPlateDoc, py::arg("scene"), py::kw_only(),
          py::arg("progress") = py::none(), py::arg("rows") = py::none());
}

}  // namespace welkin::python
