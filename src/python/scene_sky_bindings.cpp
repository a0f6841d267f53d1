// SPDX-License-Identifier: Apache-2.0
// welkin.scene_sky_image: the equirectangular sky of a scene description, its clouds
// included, as `welkin sky --scene` renders it (sky_image.hpp): the scene's atmosphere, sun,
// observer at the scene origin, sky method and options, exposure, and its clouds (layers and
// VDB volumes, lit with clouds.lighting). Thin: converts, releases the GIL, calls the core.
#include "bindings.hpp"
#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {

namespace {

constexpr const char* kSceneSkyDoc = R"doc(
The equirectangular sky of a scene, with its clouds (the world texture of a cloudy sky).

    img = welkin.scene_sky_image(scene, width, sun_disc=True, output="rgb")
    img, T = welkin.scene_sky_image(scene, width, return_transmittance=True)

scene: a welkin.SceneDescription or its JSON text. The observer stands at the scene
origin (origin_altitude_m); the sky method, its options and the exposure are the scene's;
its "clouds" (if any) are composited over the sky as in sky_image(clouds=...), lit with
clouds.lighting and clouds.scattering. Layout and units as sky_image: (width / 2, width,
3) top row first, linear Rec.709 W m^-2 sr^-1 (output="rgb") or per wavelength
("spectral"), times the exposure. return_transmittance: also the clouds' transmittance
per pixel, (width / 2, width) (ones without clouds), the factor sky_image dims the sun's
disc by (for a disc kept in an image of its own). ValueError names the parameter or the
scene's key (clouds.volumes[i].file for a bad VDB). Cancellable (progress, Ctrl-C).
ground: the lit ground below the horizon with the atmosphere's ground_albedo, as
in sky_image (False: black there).
)doc";

py::object scene_sky_image(const py::handle& scene_in, int width, bool sun_disc, const std::string& output,
                           bool return_transmittance, const py::object& progress, bool ground) {
    SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    SkyImageOptions options;
    options.sun_disc = sun_disc;
    options.ground = ground && scene.ground;
    options.ground_albedo = scene.ground_albedo;
    options.exposure = scene.exposure;
    options.color_space = scene.color_space;
    options.output = parse_output(output);
    SkyImage image;
    run_cancellable(
        [&](Progress* p) {
            if (scene.has_clouds()) {
                options.clouds = scene.cloud_density();  // opens the VDB files
                options.cloud_lighting = scene.clouds->lighting;
                options.cloud_upsampling = scene.clouds->upsampling;
                options.air_steps = scene.aerial.raymarch_steps;
            }
            const std::unique_ptr<SkyMethod> method = make_sky_method(scene.method, scene.sky_options);
            image =
                render_equirect_sky(*method, scene.atmosphere, scene.origin_observer(), width, options, p);
        },
        progress);
    const int w = image.width, h = image.height;
    std::vector<float> transmittance = std::move(image.cloud_transmittance);
    const std::size_t channels = image.channels();
    py::array_t<float> pixels = to_image_array(std::move(image.pixels), w, h, channels);
    if (!return_transmittance) return pixels;
    if (transmittance.empty()) transmittance.assign(std::size_t(w) * std::size_t(h), 1.0f);
    py::array_t<float> t({py::ssize_t(h), py::ssize_t(w)});
    std::copy(transmittance.begin(), transmittance.end(), t.mutable_data());
    return py::make_tuple(pixels, t);
}

}  // namespace

void register_scene_sky(py::module_& m) {
    m.def("scene_sky_image", &scene_sky_image, kSceneSkyDoc, py::arg("scene"), py::arg("width"),
          py::kw_only(), py::arg("sun_disc") = true, py::arg("output") = "rgb",
          py::arg("return_transmittance") = false, py::arg("progress") = py::none(),
          py::arg("ground") = true);
}

}  // namespace welkin::python
