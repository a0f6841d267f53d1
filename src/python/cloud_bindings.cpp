// SPDX-License-Identifier: Apache-2.0
// welkin.CloudLayer, welkin.VdbClouds, welkin.cloud_radiance and welkin.sky_image: the cloud
// density sources (include/welkin/clouds/procedural.hpp, clouds/vdb.hpp), their lighting
// (clouds/lighting.hpp, clouds/reference.hpp) and the equirect sky with clouds (sky_image.hpp).
// Thin: converts, releases the GIL, calls the core.
#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/reference.hpp"
#include "welkin/clouds/vdb.hpp"
#include "welkin/color/color.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/scene/clouds.hpp"

namespace welkin::python {
namespace {

// Blender's Matrix (and numpy.array(obj.matrix_world)) is indexed [row][column]; glm is
// [column][row].
glm::dmat4 to_dmat4(const py::object& m, const std::string& parameter) {
    if (m.is_none()) return glm::dmat4(1.0);
    const c_array<double> a =
        to_c_array<double>(m, parameter, 4, 2, 2, "a 4 x 4 matrix (Blender's matrix_world)");
    if (a.shape(0) != 4)
        throw_bad_shape(parameter, "a 4 x 4 matrix (Blender's matrix_world)", "shape " + shape_string(a));
    glm::dmat4 g;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) g[c][r] = a.data()[r * 4 + c];
    return g;
}

// A light spectrum given from Python: a 1-D array, one value per channel.
std::vector<float> to_spectrum(const py::object& values, const std::string& parameter) {
    const c_array<float> a =
        to_c_array<float>(values, parameter, -1, 1, 1, "a 1-D array, one value per channel");
    return std::vector<float>(a.data(), a.data() + a.shape(0));
}

std::vector<glm::dvec3> to_points(const py::object& values, const std::string& parameter) {
    const c_array<double> a = to_c_array<double>(values, parameter, 3, 2, 2, "an (N, 3) array");
    std::vector<glm::dvec3> out(std::size_t(a.shape(0)));
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = {a.data()[3 * i], a.data()[3 * i + 1], a.data()[3 * i + 2]};
    return out;
}

py::array_t<float> to_array(const std::vector<float>& v, std::vector<py::ssize_t> shape) {
    py::array_t<float> a(shape);
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
}

const char* const kCloudRadianceDoc = R"doc(
Cloud lighting for many view rays, lit by the atmosphere.

    L, T, depth = welkin.cloud_radiance(clouds, atm, altitude_m, sun_direction,
                                        view_directions, origin=(0, 0, 0),
                                        method="fast")

clouds: a welkin.CloudLayer or welkin.VdbClouds. The world origin stands altitude_m
above the ground (Blender's world frame, Z up, metres); rays start at `origin`.
method: "fast" (ray march, delta-Eddington multiple scattering) or "reference" (path tracing, all
orders; `paths` per ray). Returns L (N, C) in-scattered radiance in
W m^-2 sr^-1 nm^-1 at atm.wavelengths_nm (premultiplied), T (N,) transmittance,
depth (N,) m to the transmittance-weighted centre (0 where nothing was hit).
Composite over a background B as L + T B. ValueError for bad input.
sun_irradiance, ambient_radiance: a constant light instead of the atmosphere's (both
or neither; 1-D, one value per channel, as many channels as you like, W m^-2 and
W m^-2 sr^-1): the sun's irradiance at normal incidence everywhere and a uniform sky of
that radiance from every direction, below included (a Cycles sun lamp of that strength
and a world of that colour); atm and altitude_m then do not light the cloud.
ground_radiance: with them, the radiance from below the horizon instead (a world of one
colour above the horizon and another below); None: ambient_radiance all round.
g_forward, g_back, w_forward: the phase function, w HG(g_forward) + (1 - w) HG(g_back)
(include/welkin/clouds/phase.hpp; w_forward=1 is one Henyey-Greenstein lobe).
lighting: method "fast" only: a dict of the scene file's clouds.lighting options
(docs/pipelines.md, e.g. {"sides": False, "shadow_grid": False}), applied over
max_steps, light_steps and octaves; ValueError names a bad key as the scene file's
("clouds.lighting.sides").
)doc";

py::tuple cloud_radiance(std::shared_ptr<const CloudDensity> clouds, Atmosphere atmosphere, double altitude_m,
                         const py::object& sun_direction, const py::object& view_directions,
                         const py::object& origin, const std::string& method, int max_steps, int light_steps,
                         int octaves, double albedo, int paths, std::uint64_t seed,
                         const py::object& progress, const py::object& sun_irradiance,
                         const py::object& ambient_radiance, const py::object& ground_radiance,
                         double g_forward, double g_back, double w_forward, const py::object& lighting) {
    CloudScattering scattering;
    scattering.albedo = albedo;
    scattering.phase = CloudPhase{g_forward, g_back, w_forward};
    scattering.validate();
    if (!clouds) throw InvalidArgument("clouds", "must be a welkin.CloudLayer or welkin.VdbClouds");
    if (method != "fast" && method != "reference")
        throw InvalidArgument("method", fmt::format("must be \"fast\" or \"reference\", got \"{}\"", method));
    CloudLightingOptions fast;
    fast.max_steps = max_steps;
    fast.light_steps = light_steps;
    fast.octaves = octaves;
    fast.scattering = scattering;
    fast.seed = seed;
    if (!lighting.is_none()) {
        if (method != "fast") throw InvalidArgument("lighting", "applies to method \"fast\" only");
        if (!py::isinstance<py::dict>(lighting)) throw InvalidArgument("lighting", "must be a dict");
        apply_cloud_lighting_json(py::module_::import("json").attr("dumps")(lighting).cast<std::string>(),
                                  fast);
    }
    const Observer observer{altitude_m, to_dvec3(sun_direction, "sun_direction")};
    const glm::dvec3 o = to_dvec3(origin, "origin");
    const std::vector<glm::dvec3> dirs = to_points(view_directions, "view_directions");
    if (sun_irradiance.is_none() != ambient_radiance.is_none())
        throw InvalidArgument(sun_irradiance.is_none() ? "sun_irradiance" : "ambient_radiance",
                              "must be given together with the other (a constant light), or both left None");
    if (!ground_radiance.is_none() && sun_irradiance.is_none())
        throw InvalidArgument("ground_radiance",
                              "needs sun_irradiance and ambient_radiance (a constant light)");
    std::unique_ptr<const CloudIllumination> constant;
    if (!sun_irradiance.is_none()) {
        const std::vector<float> sky = to_spectrum(ambient_radiance, "ambient_radiance");
        const std::vector<float> ground =
            ground_radiance.is_none() ? sky : to_spectrum(ground_radiance, "ground_radiance");
        constant = std::make_unique<ConstantIllumination>(
            observer.sun_direction, to_spectrum(sun_irradiance, "sun_irradiance"), sky, ground);
    }
    CloudResult result;
    run_cancellable(
        [&](Progress* p) {
            std::unique_ptr<const CloudIllumination> from_atmosphere;
            if (!constant) from_atmosphere = std::make_unique<AtmosphereIllumination>(atmosphere, observer);
            const CloudIllumination& light = constant ? *constant : *from_atmosphere;
            if (method == "fast") {
                result = render_clouds(*clouds, light, o, dirs, fast, p);
            } else {
                CloudReferenceOptions opt;
                opt.paths = paths;
                opt.seed = seed;
                opt.scattering = scattering;
                result = render_clouds_reference(*clouds, light, o, dirs, opt, p);
            }
        },
        progress);
    const auto n = py::ssize_t(dirs.size()), c = py::ssize_t(result.channels);
    return py::make_tuple(to_array(result.radiance, {n, c}), to_array(result.transmittance, {n}),
                          to_array(result.depth_m, {n}));
}

// CloudLayer (procedural), its presets and CLOUD_TYPES.
void register_cloud_layer(py::module_& m) {
    py::class_<ProceduralClouds, CloudDensity, std::shared_ptr<ProceduralClouds>>(m, "CloudLayer", R"doc(
A procedural cloud layer on the curved planet (Schneider's Nubis: weather map,
Perlin-Worley base shape, Worley erosion with curl distortion, a height gradient per
cloud type, wind). cloud_type is a preset name: "cumulus" (the default), "stratocumulus",
"altocumulus", "stratus" or "cirrus"; every other parameter left as None takes the
preset's value (welkin.cloud_type_preset(name) lists them). Altitudes in metres above
the ground; coverage the share of the sky dome a ground observer sees covered (oktas / 8:
directions above 5 degrees whose slant optical depth reaches 0.3), or with
coverage_measure="area" the share of the ground's area under cloud (a column is cloudy
when its vertical optical depth reaches 0.3); density_per_m the extinction of the densest
cloud (m^-1); wind_offset_m carries the field (x, y in m) and evolution_m moves its noise
through the layer's height (m): keyed over time the shapes change in place;
origin_altitude_m the world origin's (observer's) altitude. ValueError names a bad
parameter.
)doc")
        .def(py::init([](const std::string& type, const py::object& bottom, const py::object& top,
                         const py::object& coverage, const std::string& coverage_measure,
                         const py::object& density, const py::object& base_scale,
                         const py::object& detail_scale, const py::object& weather_scale,
                         const py::object& detail_strength, const py::object& weather_variation,
                         const py::object& wind, double evolution, std::uint64_t seed, double planet_radius,
                         double origin_altitude) {
                 CloudLayerParams p = CloudLayerParams::preset(cloud_type_from_name(type, "cloud_type"));
                 const auto set = [](const py::object& o, const char* name, double& v) {
                     if (o.is_none()) return;
                     try {
                         v = o.cast<double>();
                     } catch (const py::cast_error&) {
                         throw InvalidArgument(name, "must be a number");
                     }
                 };
                 set(bottom, "bottom_altitude_m", p.bottom_altitude_m);
                 set(top, "top_altitude_m", p.top_altitude_m);
                 set(coverage, "coverage", p.coverage);
                 p.coverage_measure = coverage_measure_from_name(coverage_measure);
                 set(density, "density_per_m", p.density_per_m);
                 set(base_scale, "base_scale_m", p.base_scale_m);
                 set(detail_scale, "detail_scale_m", p.detail_scale_m);
                 set(weather_scale, "weather_scale_m", p.weather_scale_m);
                 set(detail_strength, "detail_strength", p.detail_strength);
                 set(weather_variation, "weather_variation", p.weather_variation);
                 const c_array<double> w =
                     to_c_array<double>(wind, "wind_offset_m", 2, 1, 1, "two numbers (x, y) in m");
                 p.wind_offset_m = {w.data()[0], w.data()[1]};
                 p.evolution_m = evolution;
                 p.seed = seed;
                 p.planet_radius_m = planet_radius;
                 p.origin_altitude_m = origin_altitude;
                 py::gil_scoped_release release;  // the noise is baked here (seconds, once per seed)
                 return std::make_shared<ProceduralClouds>(p);
             }),
             py::kw_only(), py::arg("cloud_type") = "cumulus", py::arg("bottom_altitude_m") = py::none(),
             py::arg("top_altitude_m") = py::none(), py::arg("coverage") = py::none(),
             py::arg("coverage_measure") = "dome", py::arg("density_per_m") = py::none(),
             py::arg("base_scale_m") = py::none(), py::arg("detail_scale_m") = py::none(),
             py::arg("weather_scale_m") = py::none(), py::arg("detail_strength") = py::none(),
             py::arg("weather_variation") = py::none(), py::arg("wind_offset_m") = py::make_tuple(0.0, 0.0),
             py::arg("evolution_m") = 0.0, py::arg("seed") = CloudLayerParams{}.seed,
             py::arg("planet_radius_m") = CloudLayerParams{}.planet_radius_m,
             py::arg("origin_altitude_m") = CloudLayerParams{}.origin_altitude_m)
        .def_property_readonly(
            "cloud_type",
            [](const ProceduralClouds& c) { return std::string(cloud_type_name(c.params().cloud_type)); })
        .def("covered_fraction", &ProceduralClouds::covered_fraction,
             py::arg("columns") = ProceduralClouds::kCoverageColumns,
             "The measured coverage: the share of columns whose vertical optical depth reaches 0.3.")
        .def("dome_fraction", &ProceduralClouds::dome_fraction,
             py::arg("observers") = ProceduralClouds::kDomeObservers,
             py::arg("directions") = ProceduralClouds::kDomeDirections,
             "The measured dome coverage (oktas / 8): the share of directions above 5 degrees, "
             "from ground observers, whose slant optical depth reaches 0.3.")
        .def_property_readonly("bottom_altitude_m",
                               [](const ProceduralClouds& c) { return c.params().bottom_altitude_m; })
        .def_property_readonly("top_altitude_m",
                               [](const ProceduralClouds& c) { return c.params().top_altitude_m; })
        .def_property_readonly("coverage", [](const ProceduralClouds& c) { return c.params().coverage; })
        .def_property_readonly(
            "coverage_measure",
            [](const ProceduralClouds& c) {
                return std::string(coverage_measure_name(c.params().coverage_measure));
            },
            "What coverage measures: \"dome\" (the sky a ground observer sees covered, oktas / 8) or "
            "\"area\" (the ground's area under cloud).")
        .def_property_readonly("seed", [](const ProceduralClouds& c) { return c.params().seed; });

    m.def(
        "cloud_type_preset",
        [](const std::string& name) {
            const CloudLayerParams p = CloudLayerParams::preset(cloud_type_from_name(name, "cloud_type"));
            py::dict d;
            d["cloud_type"] = std::string(cloud_type_name(p.cloud_type));
            d["bottom_altitude_m"] = p.bottom_altitude_m;
            d["top_altitude_m"] = p.top_altitude_m;
            d["coverage"] = p.coverage;
            d["density_per_m"] = p.density_per_m;
            d["base_scale_m"] = p.base_scale_m;
            d["detail_scale_m"] = p.detail_scale_m;
            d["weather_scale_m"] = p.weather_scale_m;
            d["detail_strength"] = p.detail_strength;
            d["weather_variation"] = p.weather_variation;
            return d;
        },
        py::arg("name"),
        "The layer parameters of a cloud type's preset, as a dict; ValueError lists the names.");
    m.attr("CLOUD_TYPES") =
        py::cast(std::vector<std::string>(kCloudTypeNames.begin(), kCloudTypeNames.end()));
}

// VdbClouds: clouds from an OpenVDB file.
void register_vdb_clouds(py::module_& m) {
    py::class_<VdbClouds, CloudDensity, std::shared_ptr<VdbClouds>>(m, "VdbClouds", R"doc(
Clouds from an OpenVDB file: the FloatGrid `grid` (default "density"), placed by
matrix_world (Blender's Object.matrix_world, 4 x 4, [row][column]) on top of the
grid's own transform; sigma_t = density_scale x the trilinearly interpolated value
(m^-1). negative: "clamp" (set to 0, counted in negative_voxel_count and warning) or
"reject". placement: where voxel ijk's value sits, "blender" (index ijk + 1/2, as
Blender/Cycles 3.4 show the volume object; the default) or "openvdb" (index ijk,
OpenVDB's convention). Raises OSError for a missing or corrupt file and ValueError for no such
grid, a non-float grid, an empty grid, a grid over max_memory_bytes, non-finite
values; every message names the file and the grid.
)doc")
        .def(py::init([](const std::string& path, const std::string& grid, const py::object& matrix_world,
                         double density_scale, const std::string& negative, std::uint64_t max_memory_bytes,
                         const std::string& placement) {
                 VdbCloudOptions o;
                 o.grid = grid;
                 o.matrix_world = to_dmat4(matrix_world, "matrix_world");
                 o.density_scale = density_scale;
                 if (negative != "clamp" && negative != "reject")
                     throw InvalidArgument(
                         "negative", fmt::format("must be \"clamp\" or \"reject\", got \"{}\"", negative));
                 o.negative = negative == "clamp" ? VdbCloudOptions::Negative::Clamp
                                                  : VdbCloudOptions::Negative::Reject;
                 o.max_memory_bytes = max_memory_bytes;
                 o.placement = vdb_placement_from_name(placement, "placement");
                 py::gil_scoped_release release;
                 return std::make_shared<VdbClouds>(path, o);
             }),
             py::arg("path"), py::arg("grid") = "density", py::kw_only(),
             py::arg("matrix_world") = py::none(), py::arg("density_scale") = 1.0,
             py::arg("negative") = "clamp", py::arg("max_memory_bytes") = VdbCloudOptions{}.max_memory_bytes,
             py::arg("placement") = "blender")
        .def_property_readonly("negative_voxel_count", &VdbClouds::negative_voxel_count)
        .def_property_readonly("active_voxel_count", &VdbClouds::active_voxel_count)
        .def_property_readonly("memory_bytes", &VdbClouds::memory_bytes)
        .def_property_readonly("warning", &VdbClouds::warning)
        .def_property_readonly("bounds_m", [](const VdbClouds& v) {
            const glm::dvec3 lo = v.world_bounds_min(), hi = v.world_bounds_max();
            return py::make_tuple(py::make_tuple(lo.x, lo.y, lo.z), py::make_tuple(hi.x, hi.y, hi.z));
        });
}

}  // namespace

void register_clouds(py::module_& m) {
    py::class_<CloudDensity, std::shared_ptr<CloudDensity>>(m, "CloudDensity", R"doc(
A cloud density source (base class of CloudLayer and VdbClouds).
)doc")
        .def(
            "sigma_t",
            [](const CloudDensity& d, const py::object& points) {
                const std::vector<glm::dvec3> p = to_points(points, "points");
                std::vector<float> out(p.size());
                for (std::size_t i = 0; i < p.size(); ++i) out[i] = float(d.sigma_t(p[i]));
                return to_array(out, {py::ssize_t(p.size())});
            },
            py::arg("points"), "Extinction coefficient (m^-1) at world points, (N, 3) -> (N,).");

    register_cloud_layer(m);
    register_vdb_clouds(m);

    const CloudLightingOptions lo;
    m.def("cloud_radiance", &cloud_radiance, kCloudRadianceDoc, py::arg("clouds"), py::arg("atmosphere"),
          py::arg("altitude_m"), py::arg("sun_direction"), py::arg("view_directions"), py::kw_only(),
          py::arg("origin") = py::make_tuple(0.0, 0.0, 0.0), py::arg("method") = "fast",
          py::arg("max_steps") = lo.max_steps, py::arg("light_steps") = lo.light_steps,
          py::arg("octaves") = lo.octaves, py::arg("albedo") = lo.scattering.albedo,
          py::arg("paths") = CloudReferenceOptions{}.paths, py::arg("seed") = lo.seed,
          py::arg("progress") = py::none(), py::arg("sun_irradiance") = py::none(),
          py::arg("ambient_radiance") = py::none(), py::arg("ground_radiance") = py::none(),
          py::arg("g_forward") = CloudPhase{}.g_forward, py::arg("g_back") = CloudPhase{}.g_back,
          py::arg("w_forward") = CloudPhase{}.w_forward, py::arg("lighting") = py::none());
}

}  // namespace welkin::python
