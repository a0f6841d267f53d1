// SPDX-License-Identifier: Apache-2.0
// JSON form of a SceneDescription (schema in docs/pipelines.md, "Scene JSON").
//
//   {
//     "version": 1,
//     "atmosphere": "hazy" | {atmosphere JSON, docs/pipelines.md "Atmosphere JSON"},
//     "origin_altitude_m": 0,
//     "sun": {"direction": [x, y, z]} | {"elevation_deg": 30, "azimuth_deg": 90},
//     "exposure": 1, "method": "auto",
//     "color_space": "rec709" | "rec2020" | "acescg",   // of every RGB output
//     "ground": {"enabled": true, "albedo": null},   // null: the atmosphere's ground_albedo
//     "camera": {"matrix_world": [[4 numbers] x 4 rows], "type": "PERSP" | "ORTHO" | "PANO",
//                "lens_mm", "sensor_width_mm", "sensor_height_mm", "sensor_fit", "fov_deg",
//                "ortho_scale", "panorama_type", "latitude_min_deg", "latitude_max_deg",
//                "longitude_min_deg", "longitude_max_deg", "shift_x", "shift_y",
//                "clip_start_m", "clip_end_m"},
//     "resolution": {"x": 1920, "y": 1080, "percentage": 100},
//     "aerial": {"method": "froxel" | "raymarch", "froxels": [32, 32, 32], "max_depth_m": 0,
//                "steps_per_slice": 4, "raymarch_steps": 64, "sky_depth_m": 1e9},
//     "sky_options": {"transmittance_width": 256, ...},
//     "clouds": {"layers": [...], "volumes": [...], "scattering": {...}, "lighting": {...},
//                "upsampling": {...}}
//   }
// "clouds" (scene/clouds.hpp; docs/pipelines.md "Scene JSON"), the schema the add-on writes:
// layers are CloudLayerParams without planet_radius_m / origin_altitude_m (the scene's),
// volumes {name, file, grid, matrix_world (by rows), density_scale, negative, placement}, scattering
// {albedo, g_forward, g_back, w_forward}, lighting CloudLightingOptions' other fields.
// Every key but "version" (and a camera's "matrix_world") is optional on reading (the
// defaults are scene.hpp's and camera.hpp's: a camera without "type" is "PERSP"); unknown
// keys are errors (a typo would otherwise be ignored). matrix_world is written by rows,
// as Python's [list(row) for row in camera.matrix_world] gives them. Errors name the key
// path ("camera.lens_mm").
#include "welkin/io/json.hpp"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin {
namespace {

using nlohmann::json;
using ordered_json = nlohmann::ordered_json;

int integer(const json& j, const std::string& parameter) {
    if (!j.is_number_integer())
        throw InvalidArgument(parameter, fmt::format("must be an integer, got {}", j.dump()));
    const auto v = j.get<long long>();
    if (v < -(1LL << 31) || v >= (1LL << 31))
        throw InvalidArgument(parameter, fmt::format("is out of range, got {}", v));
    return int(v);
}

std::string string(const json& j, const std::string& parameter) {
    if (!j.is_string()) throw InvalidArgument(parameter, fmt::format("must be a string, got {}", j.dump()));
    return j.get<std::string>();
}

glm::dvec3 vec3(const json& j, const std::string& parameter) {
    if (!j.is_array() || j.size() != 3)
        throw InvalidArgument(parameter, "must be an array of 3 numbers [x, y, z] (Z up)");
    return {json_number(j[0], parameter + "[0]"), json_number(j[1], parameter + "[1]"),
            json_number(j[2], parameter + "[2]")};
}

// Blender's Object.matrix_world by rows ([list(row) for row in m]) into glm's m[col][row].
glm::dmat4 matrix_rows(const json& m, const std::string& parameter) {
    if (!m.is_array() || m.size() != 4)
        throw InvalidArgument(parameter,
                              "must be 4 rows of 4 numbers (Blender's "
                              "Object.matrix_world, by rows)");
    glm::dmat4 out(1.0);
    for (int r = 0; r < 4; ++r) {
        const std::string pr = fmt::format("{}[{}]", parameter, r);
        if (!m[r].is_array() || m[r].size() != 4) throw InvalidArgument(pr, "must be a row of 4 numbers");
        for (int col = 0; col < 4; ++col)
            out[col][r] = json_number(m[r][col], fmt::format("{}[{}]", pr, col));
    }
    return out;
}

ordered_json matrix_rows_json(const glm::dmat4& m) {
    ordered_json rows = ordered_json::array();
    for (int r = 0; r < 4; ++r) rows.push_back({m[0][r], m[1][r], m[2][r], m[3][r]});
    return rows;
}

std::uint64_t unsigned_integer(const json& j, const std::string& parameter) {
    if (!j.is_number_unsigned())
        throw InvalidArgument(parameter, fmt::format("must be an integer >= 0, got {}", j.dump()));
    return j.get<std::uint64_t>();
}

bool boolean(const json& j, const std::string& parameter) {
    if (!j.is_boolean())
        throw InvalidArgument(parameter, fmt::format("must be true or false, got {}", j.dump()));
    return j.get<bool>();
}

// One of "clouds.layers" (p: its key path): the type's preset, then the keys given.
CloudLayerParams parse_cloud_layer(const json& l, const std::string& p) {
    json_check_keys(l, p,
                    {"cloud_type", "bottom_altitude_m", "top_altitude_m", "coverage", "coverage_measure",
                     "density_per_m", "base_scale_m", "detail_scale_m", "weather_scale_m", "detail_strength",
                     "weather_variation", "wind_offset_m", "evolution_m", "seed"});
    // The type's preset first (procedural.hpp), then the keys given override it.
    CloudLayerParams c;
    if (l.contains("cloud_type"))
        c = CloudLayerParams::preset(
            cloud_type_from_name(string(l["cloud_type"], p + ".cloud_type"), p + ".cloud_type"));
    const auto get = [&](const char* key, double& v) {
        if (l.contains(key)) v = json_number(l[key], p + "." + key);
    };
    get("bottom_altitude_m", c.bottom_altitude_m);
    get("top_altitude_m", c.top_altitude_m);
    get("coverage", c.coverage);
    if (l.contains("coverage_measure"))
        c.coverage_measure = coverage_measure_from_name(
            string(l["coverage_measure"], p + ".coverage_measure"), p + ".coverage_measure");
    get("density_per_m", c.density_per_m);
    get("base_scale_m", c.base_scale_m);
    get("detail_scale_m", c.detail_scale_m);
    get("weather_scale_m", c.weather_scale_m);
    get("detail_strength", c.detail_strength);
    get("weather_variation", c.weather_variation);
    if (l.contains("evolution_m")) c.evolution_m = json_number(l["evolution_m"], p + ".evolution_m");
    if (l.contains("wind_offset_m")) {
        const json& w = l["wind_offset_m"];
        if (!w.is_array() || w.size() != 2)
            throw InvalidArgument(p + ".wind_offset_m", "must be an array of 2 numbers [x, y] (m)");
        c.wind_offset_m = {json_number(w[0], p + ".wind_offset_m[0]"),
                           json_number(w[1], p + ".wind_offset_m[1]")};
    }
    if (l.contains("seed")) c.seed = unsigned_integer(l["seed"], p + ".seed");
    return c;
}

// One of "clouds.volumes" (p: its key path); a relative file is taken relative to `base`.
SceneCloudVolume parse_cloud_volume(const json& v, const std::string& p, const std::filesystem::path& base) {
    json_check_keys(v, p, {"name", "file", "grid", "matrix_world", "density_scale", "negative", "placement"});
    SceneCloudVolume vol;
    if (v.contains("name")) vol.name = string(v["name"], p + ".name");
    if (!v.contains("file"))
        throw InvalidArgument(p + ".file", "is required: the volume's .vdb file for this frame");
    const std::string file = string(v["file"], p + ".file");
    if (file.empty()) throw InvalidArgument(p + ".file", "must not be empty");
    const std::filesystem::path fp(file);
    vol.file = fp.is_absolute() || base.empty() ? file : (base / fp).lexically_normal().string();
    if (v.contains("grid")) vol.options.grid = string(v["grid"], p + ".grid");
    if (v.contains("matrix_world"))
        vol.options.matrix_world = matrix_rows(v["matrix_world"], p + ".matrix_world");
    if (v.contains("density_scale"))
        vol.options.density_scale = json_number(v["density_scale"], p + ".density_scale");
    if (v.contains("negative"))
        vol.options.negative =
            vdb_negative_from_name(string(v["negative"], p + ".negative"), p + ".negative");
    if (v.contains("placement"))
        vol.options.placement =
            vdb_placement_from_name(string(v["placement"], p + ".placement"), p + ".placement");
    return vol;
}

// "clouds.scattering" into the lighting's scattering.
void parse_cloud_scattering(const json& sc, CloudScattering& c) {
    json_check_keys(sc, "clouds.scattering", {"albedo", "g_forward", "g_back", "w_forward"});
    if (sc.contains("albedo")) c.albedo = json_number(sc["albedo"], "clouds.scattering.albedo");
    if (sc.contains("g_forward"))
        c.phase.g_forward = json_number(sc["g_forward"], "clouds.scattering.g_forward");
    if (sc.contains("g_back")) c.phase.g_back = json_number(sc["g_back"], "clouds.scattering.g_back");
    if (sc.contains("w_forward"))
        c.phase.w_forward = json_number(sc["w_forward"], "clouds.scattering.w_forward");
}

// "clouds.lighting" into CloudLightingOptions' fields but the scattering.
void parse_cloud_lighting(const json& li, CloudLightingOptions& o) {
    const std::string p = "clouds.lighting.";
    json_check_keys(
        li, "clouds.lighting",
        {"max_steps", "light_steps", "ambient_steps", "light_distance_m", "multiple_scattering", "octaves",
         "octave_extinction", "octave_contribution", "octave_eccentricity", "min_transmittance", "seed",
         "jitter", "max_distance_m", "shadow_grid", "shadow_grid_spacing_m", "sides", "surface_cut"});
    const auto geti = [&](const char* key, int& v) {
        if (li.contains(key)) v = integer(li[key], p + key);
    };
    const auto getd = [&](const char* key, double& v) {
        if (li.contains(key)) v = json_number(li[key], p + key);
    };
    geti("max_steps", o.max_steps);
    geti("surface_cut", o.surface_cut);
    geti("light_steps", o.light_steps);
    geti("ambient_steps", o.ambient_steps);
    getd("light_distance_m", o.light_distance_m);
    if (li.contains("multiple_scattering")) {
        const std::string m = string(li["multiple_scattering"], p + "multiple_scattering");
        if (m == "diffusion")
            o.multiple_scattering = CloudMultipleScattering::diffusion;
        else if (m == "octaves")
            o.multiple_scattering = CloudMultipleScattering::octaves;
        else
            throw InvalidArgument(p + "multiple_scattering",
                                  fmt::format("must be \"diffusion\" or \"octaves\", got \"{}\"", m));
    }
    geti("octaves", o.octaves);
    getd("octave_extinction", o.octave_extinction);
    getd("octave_contribution", o.octave_contribution);
    getd("octave_eccentricity", o.octave_eccentricity);
    getd("min_transmittance", o.min_transmittance);
    if (li.contains("seed")) o.seed = unsigned_integer(li["seed"], p + "seed");
    if (li.contains("jitter")) o.jitter = boolean(li["jitter"], p + "jitter");
    if (li.contains("sides")) o.sides = boolean(li["sides"], p + "sides");
    if (li.contains("shadow_grid")) o.shadow_grid = boolean(li["shadow_grid"], p + "shadow_grid");
    getd("max_distance_m", o.max_distance_m);
    getd("shadow_grid_spacing_m", o.shadow_grid_spacing_m);
}

// "clouds.upsampling".
void parse_cloud_upsampling(const json& u, CloudUpsampling& up) {
    json_check_keys(
        u, "clouds.upsampling",
        {"stride", "finest", "transmittance_tolerance", "radiance_tolerance", "max_block_size_m"});
    if (u.contains("stride")) up.stride = integer(u["stride"], "clouds.upsampling.stride");
    if (u.contains("finest")) up.finest = integer(u["finest"], "clouds.upsampling.finest");
    if (u.contains("max_block_size_m"))
        up.max_block_size_m = json_number(u["max_block_size_m"], "clouds.upsampling.max_block_size_m");
    if (u.contains("transmittance_tolerance"))
        up.transmittance_tolerance =
            json_number(u["transmittance_tolerance"], "clouds.upsampling.transmittance_tolerance");
    if (u.contains("radiance_tolerance"))
        up.radiance_tolerance = json_number(u["radiance_tolerance"], "clouds.upsampling.radiance_tolerance");
}

// "clouds" (docs/pipelines.md "Scene JSON"). Relative VDB paths are taken
// relative to `base` (the scene file's folder).
SceneClouds parse_clouds(const json& j, const std::filesystem::path& base) {
    json_check_keys(j, "clouds", {"layers", "volumes", "scattering", "lighting", "upsampling"});
    SceneClouds out;
    const auto array = [&](const char* key) -> const json& {
        const json& a = j[key];
        if (!a.is_array()) throw InvalidArgument(std::string("clouds.") + key, "must be an array of objects");
        return a;
    };
    if (j.contains("layers")) {
        const json& layers = array("layers");
        for (std::size_t i = 0; i < layers.size(); ++i)
            out.layers.push_back(parse_cloud_layer(layers[i], fmt::format("clouds.layers[{}]", i)));
    }
    if (j.contains("volumes")) {
        const json& volumes = array("volumes");
        for (std::size_t i = 0; i < volumes.size(); ++i)
            out.volumes.push_back(parse_cloud_volume(volumes[i], fmt::format("clouds.volumes[{}]", i), base));
    }
    if (j.contains("scattering")) parse_cloud_scattering(j["scattering"], out.lighting.scattering);
    if (j.contains("lighting")) parse_cloud_lighting(j["lighting"], out.lighting);
    if (j.contains("upsampling")) parse_cloud_upsampling(j["upsampling"], out.upsampling);
    return out;
}

ordered_json clouds_json(const SceneClouds& c) {
    ordered_json j;
    ordered_json layers = ordered_json::array();
    for (const CloudLayerParams& l : c.layers)
        layers.push_back({{"cloud_type", std::string(cloud_type_name(l.cloud_type))},
                          {"bottom_altitude_m", l.bottom_altitude_m},
                          {"top_altitude_m", l.top_altitude_m},
                          {"coverage", l.coverage},
                          {"coverage_measure", std::string(coverage_measure_name(l.coverage_measure))},
                          {"density_per_m", l.density_per_m},
                          {"base_scale_m", l.base_scale_m},
                          {"detail_scale_m", l.detail_scale_m},
                          {"weather_scale_m", l.weather_scale_m},
                          {"detail_strength", l.detail_strength},
                          {"weather_variation", l.weather_variation},
                          {"wind_offset_m", {l.wind_offset_m.x, l.wind_offset_m.y}},
                          {"evolution_m", l.evolution_m},
                          {"seed", l.seed}});
    j["layers"] = layers;
    ordered_json volumes = ordered_json::array();
    for (const SceneCloudVolume& v : c.volumes)
        volumes.push_back({{"name", v.name},
                           {"file", v.file},
                           {"grid", v.options.grid},
                           {"matrix_world", matrix_rows_json(v.options.matrix_world)},
                           {"density_scale", v.options.density_scale},
                           {"negative", vdb_negative_name(v.options.negative)},
                           {"placement", vdb_placement_name(v.options.placement)}});
    j["volumes"] = volumes;
    const CloudScattering& sc = c.lighting.scattering;
    j["scattering"] = {{"albedo", sc.albedo},
                       {"g_forward", sc.phase.g_forward},
                       {"g_back", sc.phase.g_back},
                       {"w_forward", sc.phase.w_forward}};
    const CloudLightingOptions& o = c.lighting;
    j["lighting"] = {{"max_steps", o.max_steps},
                     {"light_steps", o.light_steps},
                     {"ambient_steps", o.ambient_steps},
                     {"light_distance_m", o.light_distance_m},
                     {"multiple_scattering",
                      o.multiple_scattering == CloudMultipleScattering::diffusion ? "diffusion" : "octaves"},
                     {"octaves", o.octaves},
                     {"octave_extinction", o.octave_extinction},
                     {"octave_contribution", o.octave_contribution},
                     {"octave_eccentricity", o.octave_eccentricity},
                     {"min_transmittance", o.min_transmittance},
                     {"seed", o.seed},
                     {"jitter", o.jitter},
                     {"max_distance_m", o.max_distance_m},
                     {"shadow_grid", o.shadow_grid},
                     {"shadow_grid_spacing_m", o.shadow_grid_spacing_m},
                     {"sides", o.sides},
                     {"surface_cut", o.surface_cut}};
    j["upsampling"] = {{"stride", c.upsampling.stride},
                       {"finest", c.upsampling.finest},
                       {"transmittance_tolerance", c.upsampling.transmittance_tolerance},
                       {"radiance_tolerance", c.upsampling.radiance_tolerance},
                       {"max_block_size_m", c.upsampling.max_block_size_m}};
    return j;
}

// Runs f, prefixing the parameter of any InvalidArgument it throws.
template <class F>
auto prefixed(const std::string& prefix, F&& f) {
    try {
        return f();
    } catch (const InvalidArgument& e) {
        const std::string what = e.what(), own = e.parameter() + ": ";
        throw InvalidArgument(prefix + e.parameter(),
                              what.rfind(own, 0) == 0 ? what.substr(own.size()) : what);
    }
}

Camera parse_camera(const json& j) {
    json_check_keys(
        j, "camera",
        {"matrix_world", "type", "lens_mm", "sensor_width_mm", "sensor_height_mm", "sensor_fit", "fov_deg",
         "ortho_scale", "panorama_type", "latitude_min_deg", "latitude_max_deg", "longitude_min_deg",
         "longitude_max_deg", "shift_x", "shift_y", "clip_start_m", "clip_end_m"});
    Camera c;
    if (!j.contains("matrix_world"))
        throw InvalidArgument("camera.matrix_world",
                              "is required: Blender's Object.matrix_world, 4 rows of 4 numbers");
    c.matrix_world = matrix_rows(j["matrix_world"], "camera.matrix_world");
    // Absent: a perspective camera, Blender's default (Camera's own default, camera.hpp).
    if (j.contains("type")) c.type = camera_type_from_name(string(j["type"], "camera.type"), "camera.type");
    if (j.contains("fov_deg") && j.contains("lens_mm"))
        throw InvalidArgument("camera.fov_deg", "give either lens_mm or fov_deg, not both");
    if (j.contains("lens_mm")) c.lens_mm = json_number(j["lens_mm"], "camera.lens_mm");
    if (j.contains("fov_deg")) {
        c.fov_rad = json_number(j["fov_deg"], "camera.fov_deg") * kDegree;
        if (!(c.fov_rad > 0.0)) throw InvalidArgument("camera.fov_deg", "must be in (0, 179.9] degrees");
    }
    if (j.contains("sensor_width_mm"))
        c.sensor_width_mm = json_number(j["sensor_width_mm"], "camera.sensor_width_mm");
    if (j.contains("sensor_height_mm"))
        c.sensor_height_mm = json_number(j["sensor_height_mm"], "camera.sensor_height_mm");
    if (j.contains("sensor_fit"))
        c.sensor_fit =
            sensor_fit_from_name(string(j["sensor_fit"], "camera.sensor_fit"), "camera.sensor_fit");
    if (j.contains("ortho_scale")) c.ortho_scale = json_number(j["ortho_scale"], "camera.ortho_scale");
    if (j.contains("panorama_type")) {
        const std::string t = string(j["panorama_type"], "camera.panorama_type");
        if (t != "EQUIRECTANGULAR")
            throw InvalidArgument("camera.panorama_type",
                                  fmt::format("only \"EQUIRECTANGULAR\" is supported, got \"{}\" "
                                              "(fisheye and mirror-ball panoramas are not)",
                                              t));
    }
    // Blender keeps these in float32 radians: -pi/2 comes out as -90.0000025 degrees.
    // Values within 1e-3 degrees beyond the range are taken as its end.
    const auto angle = [&](const char* key, double limit_deg, double& out) {
        if (!j.contains(key)) return;
        double deg = json_number(j[key], std::string("camera.") + key);
        if (std::abs(deg) > limit_deg && std::abs(deg) < limit_deg + 1e-3)
            deg = std::copysign(limit_deg, deg);
        out = deg * kDegree;
    };
    angle("latitude_min_deg", 90.0, c.latitude_min_rad);
    angle("latitude_max_deg", 90.0, c.latitude_max_rad);
    angle("longitude_min_deg", 180.0, c.longitude_min_rad);
    angle("longitude_max_deg", 180.0, c.longitude_max_rad);
    if (j.contains("shift_x")) c.shift_x = json_number(j["shift_x"], "camera.shift_x");
    if (j.contains("shift_y")) c.shift_y = json_number(j["shift_y"], "camera.shift_y");
    if (j.contains("clip_start_m")) c.clip_start_m = json_number(j["clip_start_m"], "camera.clip_start_m");
    if (j.contains("clip_end_m")) c.clip_end_m = json_number(j["clip_end_m"], "camera.clip_end_m");
    c.validate("camera");
    return c;
}

SceneDescription parse(const json& j, const std::filesystem::path& base) {
    if (!j.is_object()) throw InvalidArgument("scene", "must be a JSON object");
    json_check_keys(
        j, "",
        {"version", "atmosphere", "origin_altitude_m", "sun", "exposure", "color_space", "method", "ground",
         "camera", "resolution", "aerial", "sky_options", "clouds", "$schema", "comment"});
    SceneDescription s;
    if (!j.contains("version"))
        throw InvalidArgument("version", fmt::format("is required (this Welkin writes version {})",
                                                     SceneDescription::kVersion));
    s.version = integer(j["version"], "version");
    if (s.version < 1 || s.version > SceneDescription::kVersion)
        throw InvalidArgument("version", fmt::format("must be in [1, {}], got {} (written by a "
                                                     "newer Welkin?)",
                                                     SceneDescription::kVersion, s.version));
    if (j.contains("atmosphere")) {
        const json& a = j["atmosphere"];
        if (a.is_string())
            s.atmosphere = prefixed("atmosphere.", [&] { return Atmosphere::preset(a.get<std::string>()); });
        else if (a.is_object())
            s.atmosphere = prefixed("atmosphere.", [&] { return Atmosphere::from_json_string(a.dump()); });
        else
            throw InvalidArgument("atmosphere", "must be a preset name or an atmosphere object");
    }
    if (j.contains("origin_altitude_m"))
        s.origin_altitude_m = json_number(j["origin_altitude_m"], "origin_altitude_m");
    if (j.contains("sun")) {
        const json& sun = j["sun"];
        json_check_keys(sun, "sun", {"direction", "elevation_deg", "azimuth_deg"});
        const bool by_angles = sun.contains("elevation_deg") || sun.contains("azimuth_deg");
        if (sun.contains("direction") == by_angles)
            throw InvalidArgument("sun",
                                  "give either \"direction\" [x, y, z] or "
                                  "\"elevation_deg\" and \"azimuth_deg\"");
        if (by_angles) {
            if (!sun.contains("elevation_deg") || !sun.contains("azimuth_deg"))
                throw InvalidArgument("sun", "needs both \"elevation_deg\" and \"azimuth_deg\"");
            s.sun_direction =
                sun_direction_from_angles_deg(json_number(sun["elevation_deg"], "sun.elevation_deg"),
                                              json_number(sun["azimuth_deg"], "sun.azimuth_deg"));
        } else {
            s.sun_direction = vec3(sun["direction"], "sun.direction");
        }
    }
    if (j.contains("exposure")) s.exposure = json_number(j["exposure"], "exposure");
    if (j.contains("color_space"))
        s.color_space = color_space_from_name(string(j["color_space"], "color_space"));
    if (j.contains("method")) s.method = string(j["method"], "method");
    if (j.contains("ground")) {
        const json& g = j["ground"];
        json_check_keys(g, "ground", {"enabled", "albedo"});
        if (g.contains("enabled")) s.ground = boolean(g["enabled"], "ground.enabled");
        if (g.contains("albedo") && !g["albedo"].is_null())
            s.ground_albedo = json_number(g["albedo"], "ground.albedo");
    }
    if (j.contains("camera") && !j["camera"].is_null()) s.camera = parse_camera(j["camera"]);
    if (j.contains("resolution")) {
        const json& r = j["resolution"];
        json_check_keys(r, "resolution", {"x", "y", "percentage"});
        if (r.contains("x")) s.resolution.x = integer(r["x"], "resolution.x");
        if (r.contains("y")) s.resolution.y = integer(r["y"], "resolution.y");
        if (r.contains("percentage"))
            s.resolution.percentage = integer(r["percentage"], "resolution.percentage");
    }
    if (j.contains("aerial")) {
        const json& a = j["aerial"];
        json_check_keys(
            a, "aerial",
            {"method", "froxels", "max_depth_m", "steps_per_slice", "raymarch_steps", "sky_depth_m"});
        AerialOptions& o = s.aerial;
        if (a.contains("method")) o.method = aerial_method_from_name(string(a["method"], "aerial.method"));
        if (a.contains("froxels")) {
            const json& f = a["froxels"];
            if (!f.is_array() || f.size() != 3)
                throw InvalidArgument("aerial.froxels", "must be [columns, rows, slices]");
            o.froxel_width = integer(f[0], "aerial.froxels[0]");
            o.froxel_height = integer(f[1], "aerial.froxels[1]");
            o.froxel_slices = integer(f[2], "aerial.froxels[2]");
        }
        if (a.contains("max_depth_m")) o.max_depth_m = json_number(a["max_depth_m"], "aerial.max_depth_m");
        if (a.contains("steps_per_slice"))
            o.steps_per_slice = integer(a["steps_per_slice"], "aerial.steps_per_slice");
        if (a.contains("raymarch_steps"))
            o.raymarch_steps = integer(a["raymarch_steps"], "aerial.raymarch_steps");
        if (a.contains("sky_depth_m")) o.sky_depth_m = json_number(a["sky_depth_m"], "aerial.sky_depth_m");
    }
    if (j.contains("sky_options")) {
        const json& o = j["sky_options"];
        json_check_keys(
            o, "sky_options",
            {"transmittance_width", "transmittance_height", "multiscattering_size", "skyview_width",
             "skyview_height", "raymarch_steps", "raymarch_sun_steps", "reference_paths", "seed"});
        SkyOptions& k = s.sky_options;
        const auto get = [&](const char* key, int& out) {
            if (o.contains(key)) out = integer(o[key], std::string("sky_options.") + key);
        };
        get("transmittance_width", k.transmittance_width);
        get("transmittance_height", k.transmittance_height);
        get("multiscattering_size", k.multiscattering_size);
        get("skyview_width", k.skyview_width);
        get("skyview_height", k.skyview_height);
        get("raymarch_steps", k.raymarch_steps);
        get("raymarch_sun_steps", k.raymarch_sun_steps);
        get("reference_paths", k.reference_paths);
        if (o.contains("seed")) {
            if (!o["seed"].is_number_unsigned())
                throw InvalidArgument("sky_options.seed", "must be an integer >= 0");
            k.seed = o["seed"].get<std::uint64_t>();
        }
    }
    if (j.contains("clouds") && !j["clouds"].is_null()) s.clouds = parse_clouds(j["clouds"], base);
    s.validate();
    return s;
}

}  // namespace

void apply_cloud_lighting_json(const std::string& text, CloudLightingOptions& options) {
    const json j = parse_json(text, "clouds.lighting");
    if (!j.is_object()) throw InvalidArgument("clouds.lighting", "must be a JSON object");
    parse_cloud_lighting(j, options);
    prefixed("clouds.lighting.", [&] { options.validate(); });
}

SceneDescription SceneDescription::from_json_string(const std::string& text,
                                                    const std::string& base_directory) {
    const json j = parse_json(text, "scene JSON");
    return parse(j, base_directory.empty()
                        ? std::filesystem::path()
                        : std::filesystem::absolute(std::filesystem::path(base_directory)));
}

SceneDescription SceneDescription::from_json_file(const std::string& path) {
    const json j = read_json_file(path, "scene");
    std::error_code ec;
    const std::filesystem::path dir =
        std::filesystem::absolute(std::filesystem::path(path), ec).parent_path();
    return parse(j, dir);
}

std::string SceneDescription::to_json_string() const {
    validate();
    ordered_json j;
    j["version"] = version;
    j["atmosphere"] = ordered_json::parse(atmosphere.to_json_string());
    j["origin_altitude_m"] = origin_altitude_m;
    j["sun"] = {{"direction", {sun_direction.x, sun_direction.y, sun_direction.z}}};
    j["exposure"] = exposure;
    j["color_space"] = color_space_name(color_space);
    j["method"] = method;
    j["ground"] = {{"enabled", ground},
                   {"albedo", ground_albedo ? ordered_json(*ground_albedo) : ordered_json(nullptr)}};
    if (camera) {
        const Camera& c = *camera;
        ordered_json cj;
        cj["matrix_world"] = matrix_rows_json(c.matrix_world);
        cj["type"] = camera_type_name(c.type);
        if (c.fov_rad > 0.0)
            cj["fov_deg"] = c.fov_rad / kDegree;
        else
            cj["lens_mm"] = c.lens_mm;
        cj["sensor_width_mm"] = c.sensor_width_mm;
        cj["sensor_height_mm"] = c.sensor_height_mm;
        cj["sensor_fit"] = sensor_fit_name(c.sensor_fit);
        cj["ortho_scale"] = c.ortho_scale;
        if (c.type == CameraType::Panoramic) cj["panorama_type"] = "EQUIRECTANGULAR";
        cj["latitude_min_deg"] = c.latitude_min_rad / kDegree;
        cj["latitude_max_deg"] = c.latitude_max_rad / kDegree;
        cj["longitude_min_deg"] = c.longitude_min_rad / kDegree;
        cj["longitude_max_deg"] = c.longitude_max_rad / kDegree;
        cj["shift_x"] = c.shift_x;
        cj["shift_y"] = c.shift_y;
        cj["clip_start_m"] = c.clip_start_m;
        cj["clip_end_m"] = c.clip_end_m;
        j["camera"] = cj;
    }
    j["resolution"] = {{"x", resolution.x}, {"y", resolution.y}, {"percentage", resolution.percentage}};
    j["aerial"] = {{"method", aerial_method_name(aerial.method)},
                   {"froxels", {aerial.froxel_width, aerial.froxel_height, aerial.froxel_slices}},
                   {"max_depth_m", aerial.max_depth_m},
                   {"steps_per_slice", aerial.steps_per_slice},
                   {"raymarch_steps", aerial.raymarch_steps},
                   {"sky_depth_m", aerial.sky_depth_m}};
    const SkyOptions& k = sky_options;
    j["sky_options"] = {{"transmittance_width", k.transmittance_width},
                        {"transmittance_height", k.transmittance_height},
                        {"multiscattering_size", k.multiscattering_size},
                        {"skyview_width", k.skyview_width},
                        {"skyview_height", k.skyview_height},
                        {"raymarch_steps", k.raymarch_steps},
                        {"raymarch_sun_steps", k.raymarch_sun_steps},
                        {"reference_paths", k.reference_paths},
                        {"seed", k.seed}};
    if (clouds) j["clouds"] = clouds_json(*clouds);
    return j.dump(2);
}

void SceneDescription::to_json_file(const std::string& path, bool overwrite) const {
    write_json_file(path, to_json_string(), overwrite);
}

}  // namespace welkin
