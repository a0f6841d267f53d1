// SPDX-License-Identifier: Apache-2.0
// welkin.sky_image, welkin.sun_disc_image: the core's equirectangular sky images
// (include/welkin/render/sky_image.hpp) as numpy arrays, for the Blender add-on and scripts.
//
// Thin, like the other bindings: arguments are converted, the GIL is released, the core
// computes, and its pixel buffer becomes the returned array without a copy.
#include <memory>

#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/density.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/sky/method.hpp"

namespace welkin::python {

SkyImageOptions::Output parse_output(const std::string& output) {
    if (output == "rgb") return SkyImageOptions::Output::Rgb;
    if (output == "spectral") return SkyImageOptions::Output::Spectral;
    throw InvalidArgument("output", fmt::format("must be \"rgb\" or \"spectral\", got \"{}\"", output));
}

namespace {

py::array_t<float> render(const SkyMethod& method, const Atmosphere& atmosphere, double altitude_m,
                          const py::object& sun_direction, int width, const SkyImageOptions& options,
                          const py::object& progress) {
    require_progress_callback(progress);
    const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};
    SkyImage image;
    run_cancellable(
        [&](Progress* p) { image = render_equirect_sky(method, atmosphere, observer, width, options, p); },
        progress);
    const std::size_t channels = image.channels();
    return to_image_array(std::move(image.pixels), image.width, image.height, channels);
}

py::array_t<float> sky_image(Atmosphere atmosphere, double altitude_m, const py::object& sun_direction,
                             int width, const std::string& method, const std::string& output, bool sun_disc,
                             double exposure, int steps, int sun_steps, int paths, std::uint64_t seed,
                             std::shared_ptr<const CloudDensity> clouds, const py::object& progress,
                             bool ground, std::optional<double> ground_albedo,
                             const std::string& color_space) {
    SkyImageOptions options;
    options.color_space = color_space_from_name(color_space);
    options.clouds = std::move(clouds);
    options.sun_disc = sun_disc;
    options.ground = ground;
    options.ground_albedo = ground_albedo;
    options.exposure = exposure;
    options.output = parse_output(output);
    SkyOptions sky_options;
    sky_options.raymarch_steps = steps;
    sky_options.raymarch_sun_steps = sun_steps;
    sky_options.reference_paths = paths;
    sky_options.seed = seed;
    const std::unique_ptr<SkyMethod> sky = make_sky_method(method, sky_options);
    return render(*sky, atmosphere, altitude_m, sun_direction, width, options, progress);
}

// The sky term of render_equirect_sky set to zero, so that its image is the sun's disc
// alone: the same supersampled, energy-exact splat as in sky_image(sun_disc=True).
class NoSky final : public SkyMethod {
public:
    std::string name() const override { return "none"; }
    void radiance(const Atmosphere&, const Observer&, std::span<const glm::dvec3>, std::span<float> out,
                  std::span<float> standard_error, Progress*) const override {
        std::fill(out.begin(), out.end(), 0.0f);
        std::fill(standard_error.begin(), standard_error.end(), 0.0f);
    }
};

py::array_t<float> sun_disc_image(Atmosphere atmosphere, double altitude_m, const py::object& sun_direction,
                                  int width, const std::string& output, double exposure,
                                  const std::string& color_space) {
    SkyImageOptions options;
    options.color_space = color_space_from_name(color_space);
    options.sun_disc = true;
    options.ground = false;
    options.exposure = exposure;
    options.output = parse_output(output);
    return render(NoSky(), atmosphere, altitude_m, sun_direction, width, options, py::none());
}

}  // namespace

void register_image(py::module_& m) {
    const SkyOptions defaults;
    m.def("sky_image", &sky_image, py::arg("atmosphere"), py::arg("altitude_m"), py::arg("sun_direction"),
          py::arg("width"), py::arg("method") = "lut", py::arg("output") = "rgb", py::kw_only(),
          py::arg("sun_disc") = true, py::arg("exposure") = 1.0, py::arg("steps") = defaults.raymarch_steps,
          py::arg("sun_steps") = defaults.raymarch_sun_steps, py::arg("paths") = defaults.reference_paths,
          py::arg("seed") = defaults.seed, py::arg("clouds") = py::none(), py::arg("progress") = py::none(),
          py::arg("ground") = true, py::arg("ground_albedo") = py::none(), py::arg("color_space") = "rec709",
          R"doc(
An equirectangular sky image (HDRI) of the whole sphere, as the CLI renders it.

    img = welkin.sky_image(atm, altitude_m, sun_direction, width, method="lut",
                           output="rgb", sun_disc=True, exposure=1.0, clouds=None)

Blender's Environment Texture mapping (see direction_to_equirect), width x
width/2 pixels (width even, 4..16384), TOP ROW (zenith) FIRST as in EXR files;
Blender's own images are bottom row first (flip rows before Image.pixels).
Returns float32 (height, width, 3) linear RGB of color_space ("rec709",
"rec2020" or "acescg": the spectrum's CIE XYZ through that space's matrix,
color_space.hpp) in W m^-2 sr^-1 for output="rgb", or (height, width, C) W m^-2 sr^-1 nm^-1 at atm.wavelengths_nm for
"spectral"; every value times exposure. sun_disc adds the sun's disc, limb
darkened and scaled so that the image delivers exactly welkin.sun()'s direct
irradiance; leave it out when a sun lamp lights the scene. steps, sun_steps,
paths, seed: as in sky_radiance. clouds: None, a welkin.CloudLayer or a
welkin.VdbClouds, composited over the sky (lit by the same atmosphere; the sun's
disc dimmed behind them). ground: the planet's surface below the horizon, lit
by the sun and the sky and seen through the air (False: black there);
ground_albedo: its albedo in [0, 1] (None: atm.ground_albedo). The GIL is released; Ctrl-C or a progress
callback returning False cancels (KeyboardInterrupt). ValueError names the
parameter for bad input.
)doc");

    m.def("sun_disc_image", &sun_disc_image, py::arg("atmosphere"), py::arg("altitude_m"),
          py::arg("sun_direction"), py::arg("width"), py::arg("output") = "rgb", py::kw_only(),
          py::arg("exposure") = 1.0, py::arg("color_space") = "rec709", R"doc(
The sun's disc alone, in the layout and units of sky_image: the term that
sky_image(sun_disc=True) adds to sky_image(sun_disc=False). Zero everywhere but
the few pixels the disc touches (none when the sun is below the horizon).
)doc");
}

}  // namespace welkin::python
