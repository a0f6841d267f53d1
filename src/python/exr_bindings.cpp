// SPDX-License-Identifier: Apache-2.0
// welkin.write_exr, welkin.read_exr: the core's OpenEXR files (include/welkin/io/exr.hpp)
// from and to numpy arrays, top row first. Thin: the core's writer is atomic and never
// replaces a file unless asked.
#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/io/exr.hpp"

namespace welkin::python {
namespace {

std::size_t write_exr_file(const std::string& path, const py::object& pixels, const py::object& channel_names,
                           bool half, bool overwrite,
                           const std::vector<std::pair<std::string, std::string>>& attributes) {
    const c_array<float> in =
        to_c_array<float>(pixels, "pixels", -1, 3, 3, "a (height, width, channels) array");
    ExrImage image;
    image.height = int(in.shape(0));
    image.width = int(in.shape(1));
    const auto channels = std::size_t(in.shape(2));
    if (channel_names.is_none()) {
        if (channels != 3 && channels != 4)
            throw InvalidArgument("channel_names", fmt::format("must be given for {} channels (the default "
                                                               "names R, G, B[, A] need 3 or 4)",
                                                               channels));
        image.channel_names = {"R", "G", "B"};
        if (channels == 4) image.channel_names.push_back("A");
    } else {
        image.channel_names = channel_names.cast<std::vector<std::string>>();
        if (image.channel_names.size() != channels)
            throw InvalidArgument("channel_names", fmt::format("must name each of the {} channels of pixels, "
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
    return py::make_tuple(to_image_array(std::move(image.pixels), image.width, image.height, channels),
                          names);
}

}  // namespace

void register_exr(py::module_& m) {
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
