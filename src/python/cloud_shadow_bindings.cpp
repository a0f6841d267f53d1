// SPDX-License-Identifier: Apache-2.0
// welkin.cloud_transmittance: the clouds of a scene description, their transmittance
// towards a distant light from many points (clouds/shadow.hpp). Thin: converts, releases
// the GIL, calls the core.
#include "bindings.hpp"

#include "welkin/clouds/shadow.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {

namespace {

constexpr const char* kCloudTransmittanceDoc = R"doc(
The clouds' transmittance towards a distant light, from many points.

    T = welkin.cloud_transmittance(scene, points, direction=None, steps=64,
                                   max_distance_m=1e6)

scene: a welkin.SceneDescription or its JSON text; its clouds (layers and VDB volumes)
in the scene's frame (Blender's world frame, Z up, metres; the origin origin_altitude_m
above the ground). points: (N, 3) metres. direction: towards the light (normalised here;
default the scene's sun_direction). Returns T (N,) float32, exp(-optical depth) of the
clouds along each ray (the air not included); ones for a scene without clouds. steps:
march steps per ray (midpoint rule over the clouds' extent). ValueError names the
parameter. Cancellable (progress, Ctrl-C).
)doc";

py::array_t<float> cloud_transmittance_py(const py::handle& scene_in, const py::object& points_in,
                                          const py::object& direction_in, int steps, double max_distance_m,
                                          const py::object& progress) {
    const SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    const c_array<double> a = to_c_array<double>(points_in, "points", 3, 2, 2, "an (N, 3) array");
    std::vector<glm::dvec3> storage;
    const std::span<const glm::dvec3> points = as_dvec3_span(a, storage);
    const glm::dvec3 direction =
        direction_in.is_none() ? scene.sun_direction : to_dvec3(direction_in, "direction");
    CloudShadowOptions options;
    options.steps = steps;
    options.max_distance_m = max_distance_m;
    options.validate();
    std::vector<float> t(points.size(), 1.0f);
    if (scene.has_clouds()) {
        run_cancellable(
            [&](Progress* p) {
                const auto density = scene.cloud_density();  // opens the VDB files
                t = cloud_transmittance(*density, points, direction, options, p);
            },
            progress);
    }
    py::array_t<float> out(py::ssize_t(t.size()));
    std::copy(t.begin(), t.end(), out.mutable_data());
    return out;
}

}  // namespace

void register_cloud_shadow(py::module_& m) {
    m.def("cloud_transmittance", &cloud_transmittance_py, kCloudTransmittanceDoc, py::arg("scene"),
          py::arg("points"), py::arg("direction") = py::none(), py::kw_only(), py::arg("steps") = 64,
          py::arg("max_distance_m") = 1.0e6, py::arg("progress") = py::none());
}

}  // namespace welkin::python
