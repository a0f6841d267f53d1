// welkin.sky_image, welkin.sun_disc_image, welkin.write_exr, welkin.read_exr: the core's
// equirectangular sky images (include/welkin/sky_image.hpp) and OpenEXR files
// (include/welkin/exr_io.hpp) as numpy arrays, for the Blender add-on and scripts.
//
// Thin, like the other bindings: arguments are converted, the GIL is released, the core
// computes, and its pixel buffer becomes the returned array without a copy.
#include <memory>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "welkin/error.hpp"
#include "welkin/exr_io.hpp"
#include "welkin/sky_image.hpp"
#include "welkin/sky_method.hpp"

namespace welkin::python {
namespace {

// A (height, width, channels) float32 array that owns `pixels` (moved, not copied).
py::array_t<float> to_image_array(std::vector<float>&& pixels, int width, int height,
                                  std::size_t channels) {
    auto* owner = new std::vector<float>(std::move(pixels));
    py::capsule free_when_done(owner, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>({py::ssize_t(height), py::ssize_t(width), py::ssize_t(channels)},
                              owner->data(), free_when_done);
}

SkyImageOptions::Output parse_output(const std::string& output) {
    if (output == "rgb") return SkyImageOptions::Output::Rgb;
    if (output == "spectral") return SkyImageOptions::Output::Spectral;
    throw InvalidArgument("output", fmt::format("must be \"rgb\" or \"spectral\", got \"{}\"",
                                                output));
}

py::array_t<float> render(const SkyMethod& method, const Atmosphere& atmosphere,
                          double altitude_m, const py::object& sun_direction, int width,
                          const SkyImageOptions& options, const py::object& progress) {
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
        throw py::type_error("progress: must be a callable taking the fraction done, or None");
    const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};
    SkyImage image;
    run_cancellable(
        [&](Progress* p) {
            image = render_equirect_sky(method, atmosphere, observer, width, options, p);
        },
        progress);
    const std::size_t channels = image.channels();
    return to_image_array(std::move(image.pixels), image.width, image.height, channels);
}

py::array_t<float> sky_image(Atmosphere atmosphere, double altitude_m,
                             const py::object& sun_direction, int width,
                             const std::string& method, const std::string& output,
                             bool sun_disc, double exposure, int steps, int sun_steps,
                             int paths, std::uint64_t seed, const py::object& progress) {
    SkyImageOptions options;
    options.sun_disc = sun_disc;
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
    void radiance(const Atmosphere&, const Observer&, std::span<const glm::dvec3>,
                  std::span<float> out, std::span<float> standard_error,
                  Progress*) const override {
        std::fill(out.begin(), out.end(), 0.0f);
        std::fill(standard_error.begin(), standard_error.end(), 0.0f);
    }
};

py::array_t<float> sun_disc_image(Atmosphere atmosphere, double altitude_m,
                                  const py::object& sun_direction, int width,
                                  const std::string& output, double exposure) {
    SkyImageOptions options;
    options.sun_disc = true;
    options.exposure = exposure;
    options.output = parse_output(output);
    return render(NoSky(), atmosphere, altitude_m, sun_direction, width, options, py::none());
}

std::size_t write_exr_file(const std::string& path, const py::object& pixels,
                           const py::object& channel_names, bool half, bool overwrite,
                           const std::vector<std::pair<std::string, std::string>>& attributes) {
    const c_array<float> in = to_c_array<float>(pixels, "pixels", -1, 3, 3,
                                                "a (height, width, channels) array");
    ExrImage image;
    image.height = int(in.shape(0));
    image.width = int(in.shape(1));
    const auto channels = std::size_t(in.shape(2));
    if (channel_names.is_none()) {
        if (channels != 3 && channels != 4)
            throw InvalidArgument("channel_names",
                                  fmt::format("must be given for {} channels (the default "
                                              "names R, G, B[, A] need 3 or 4)",
                                              channels));
        image.channel_names = {"R", "G", "B"};
        if (channels == 4) image.channel_names.push_back("A");
    } else {
        image.channel_names = channel_names.cast<std::vector<std::string>>();
        if (image.channel_names.size() != channels)
            throw InvalidArgument("channel_names",
                                  fmt::format("must name each of the {} channels of pixels, "
                                              "got {} names",
                                              channels, image.channel_names.size()));
    }
    image.pixels.assign(in.data(), in.data() + in.size());
    ExrWriteOptions options;
    options.pixel_type = half ? ExrPixelType::Half : ExrPixelType::Float;
    options.overwrite = overwrite;
    options.attributes = attributes;
    py::gil_scoped_release release;
    return write_exr(path, image, options).clamped_values;
}

py::tuple read_exr_file(const std::string& path) {
    ExrImage image;
    {
        py::gil_scoped_release release;
        image = read_exr(path);
    }
    const std::size_t channels = image.channels();
    py::list names;
    for (const std::string& name : image.channel_names) names.append(name);
    return py::make_tuple(
        to_image_array(std::move(image.pixels), image.width, image.height, channels), names);
}

}  // namespace

void register_image(py::module_& m) {
    const SkyOptions defaults;
    m.def("sky_image", &sky_image, py::arg("atmosphere"), py::arg("altitude_m"),
          py::arg("sun_direction"), py::arg("width"), py::arg("method") = "lut",
          py::arg("output") = "rgb", py::kw_only(), py::arg("sun_disc") = true,
          py::arg("exposure") = 1.0, py::arg("steps") = defaults.raymarch_steps,
          py::arg("sun_steps") = defaults.raymarch_sun_steps,
          py::arg("paths") = defaults.reference_paths, py::arg("seed") = defaults.seed,
          py::arg("progress") = py::none(), R"doc(
An equirectangular sky image (HDRI) of the whole sphere, as the CLI renders it.

    img = welkin.sky_image(atm, altitude_m, sun_direction, width, method="lut",
                           output="rgb", sun_disc=True, exposure=1.0)

Blender's Environment Texture mapping (see direction_to_equirect), width x
width/2 pixels (width even, 4..16384), TOP ROW (zenith) FIRST as in EXR files;
Blender's own images are bottom row first (flip rows before Image.pixels).
Returns float32 (height, width, 3) linear Rec.709 in W m^-2 sr^-1 for
output="rgb", or (height, width, C) W m^-2 sr^-1 nm^-1 at atm.wavelengths_nm for
"spectral"; every value times exposure. sun_disc adds the sun's disc, limb
darkened and scaled so that the image delivers exactly welkin.sun()'s direct
irradiance; leave it out when a sun lamp lights the scene. steps, sun_steps,
paths, seed: as in sky_radiance. The GIL is released; Ctrl-C or a progress
callback returning False cancels (KeyboardInterrupt). ValueError names the
parameter for bad input.
)doc");

    m.def("sun_disc_image", &sun_disc_image, py::arg("atmosphere"), py::arg("altitude_m"),
          py::arg("sun_direction"), py::arg("width"), py::arg("output") = "rgb", py::kw_only(),
          py::arg("exposure") = 1.0, R"doc(
The sun's disc alone, in the layout and units of sky_image: the term that
sky_image(sun_disc=True) adds to sky_image(sun_disc=False). Zero everywhere but
the few pixels the disc touches (none when the sun is below the horizon).
)doc");

    m.def("write_exr", &write_exr_file, py::arg("path"), py::arg("pixels"),
          py::arg("channel_names") = py::none(), py::kw_only(), py::arg("half") = false,
          py::arg("overwrite") = false,
          py::arg("attributes") = std::vector<std::pair<std::string, std::string>>{}, R"doc(
Writes a (height, width, channels) array, top row first, as OpenEXR (ZIP).

channel_names defaults to R, G, B (and A for 4 channels). half=True stores half
floats (finite values beyond 65504 are clamped to it); float otherwise.
attributes: [(name, text), ...] extra header strings. The file is written to a
temporary name and moved into place; an existing file is never replaced unless
overwrite=True (OSError naming the path otherwise). Returns the number of
values clamped to the half range.
)doc");

    m.def("read_exr", &read_exr_file, py::arg("path"), R"doc(
Reads an OpenEXR file: returns (pixels, channel_names), pixels float32
(height, width, channels), top row first, channels in the file's (sorted)
order. OSError naming the path on failure.
)doc");
}

}  // namespace welkin::python
