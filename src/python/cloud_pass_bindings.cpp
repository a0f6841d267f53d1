// SPDX-License-Identifier: Apache-2.0
// welkin.cloud_passes: the scene camera's Welkin.Clouds and Welkin.CloudDepth passes
// (include/welkin/render/cloud_passes.hpp) as numpy arrays. Thin: converts, releases the GIL,
// calls the core.
#include <optional>
#include <utility>

#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/base/row_range.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {
namespace {

constexpr const char* kCloudPassesDoc = R"doc(
The scene camera's cloud passes, for compositing over a render (cloud_passes.hpp).

    passes = welkin.cloud_passes(scene, depth=None, progress=None, rows=None)

scene    : welkin.SceneDescription or its JSON text, with a camera and "clouds"
           (procedural layers and/or VDB volumes; the VDB files are opened here)
depth    : None (no geometry: every ray runs to clouds.lighting.max_distance_m) or the
           render's Z pass, (height, width) float, metres (Blender's convention), rows
           top first; +inf or >= aerial.sky_depth_m is sky. Rays end at the geometry.
progress : callable(fraction) -> bool or None; returning False cancels (KeyboardInterrupt)
rows     : None or (begin, end): only rows [begin, end) from the top, with the whole
           frame's values there

Returns {"Welkin.Clouds": (height, width, 4) float32, premultiplied RGBA, linear
Rec.709 W m^-2 sr^-1 times the exposure, the air between the camera and the cloud
included; "Welkin.CloudDepth": (height, width) float32, the cloud's depth in
Blender's Z convention, 1e10 where there is no cloud}. Composite:
    final = Clouds.rgb + (1 - Clouds.a) * (Image * AerialTransmittance + AerialInscatter)
Raises ValueError naming the field: no camera ("camera"), no clouds ("clouds"), a bad
volume ("clouds.volumes[i].file", with the file's path and the reason), a depth of the
wrong shape or with NaN / negative values ("depth"), a bad row range ("rows").
)doc";

py::dict cloud_passes_py(const py::handle& scene_in, const py::object& depth_in, const py::object& progress,
                         const std::optional<std::pair<int, int>>& rows) {
    SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    scene.require_camera();
    const int width = scene.resolution.width(), height = scene.resolution.height();
    std::vector<float> depth;
    if (!depth_in.is_none()) {
        const c_array<float> d =
            to_c_array<float>(depth_in, "depth", -1, 2, 2, "a (height, width) array of depths in metres");
        if (d.shape(0) != height || d.shape(1) != width)
            throw InvalidArgument("depth", fmt::format("has shape ({}, {}) but the scene renders {} x {} "
                                                       "(shape ({}, {}))",
                                                       d.shape(0), d.shape(1), width, height, height, width));
        depth.assign(d.data(), d.data() + d.size());
    }
    RowRange band;
    if (rows) band = RowRange{rows->first, rows->second}.resolved(height);
    CloudPasses passes;
    run_cancellable([&](Progress* p) { passes = render_cloud_passes(scene, depth, p, band); }, progress);
    const int w = passes.width, h = passes.height;
    py::dict out;
    out["Welkin.Clouds"] = to_image_array(std::move(passes.clouds), w, h, 4);
    py::array_t<float> z({py::ssize_t(h), py::ssize_t(w)});
    std::copy(passes.depth.begin(), passes.depth.end(), z.mutable_data());
    out["Welkin.CloudDepth"] = z;
    return out;
}

}  // namespace

void register_cloud_passes(py::module_& m) {
    m.def("cloud_passes", &cloud_passes_py, kCloudPassesDoc, py::arg("scene"), py::arg("depth") = py::none(),
          py::kw_only(), py::arg("progress") = py::none(), py::arg("rows") = py::none());
}

}  // namespace welkin::python
