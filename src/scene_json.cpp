// JSON form of a SceneDescription (schema in README.md, "Scene JSON").
//
//   {
//     "version": 1,
//     "atmosphere": "hazy" | {atmosphere JSON, README "Atmosphere JSON"},
//     "origin_altitude_m": 0,
//     "sun": {"direction": [x, y, z]} | {"elevation_deg": 30, "azimuth_deg": 90},
//     "exposure": 1, "method": "auto",
//     "camera": {"matrix_world": [[4 numbers] x 4 rows], "type": "PERSP" | "ORTHO" | "PANO",
//                "lens_mm", "sensor_width_mm", "sensor_height_mm", "sensor_fit", "fov_deg",
//                "ortho_scale", "panorama_type", "latitude_min_deg", "latitude_max_deg",
//                "longitude_min_deg", "longitude_max_deg", "shift_x", "shift_y",
//                "clip_start_m", "clip_end_m"},
//     "resolution": {"x": 1920, "y": 1080, "percentage": 100},
//     "aerial": {"method": "froxel" | "raymarch", "froxels": [32, 32, 32], "max_depth_m": 0,
//                "steps_per_slice": 4, "raymarch_steps": 64, "sky_depth_m": 1e9},
//     "sky_options": {"transmittance_width": 256, ...}
//   }
// Every key but "version" is optional on reading (the defaults are scene.hpp's); unknown
// keys are errors (a typo would otherwise be ignored). matrix_world is written by rows,
// as Python's [list(row) for row in camera.matrix_world] gives them. Errors name the key
// path ("camera.lens_mm").
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "welkin/error.hpp"
#include "welkin/math.hpp"
#include "welkin/scene.hpp"

namespace welkin {
namespace {

using nlohmann::json;
using ordered_json = nlohmann::ordered_json;

void check_keys(const json& j, const std::string& where, std::initializer_list<const char*> known) {
    if (!j.is_object()) throw InvalidArgument(where.empty() ? "scene" : where, "must be a JSON object");
    for (const auto& [key, _] : j.items()) {
        bool ok = false;
        for (const char* k : known) ok = ok || key == k;
        if (!ok)
            throw InvalidArgument(where.empty() ? key : where + "." + key, "unknown key (a typo?)");
    }
}

double number(const json& j, const std::string& parameter) {
    if (!j.is_number())
        throw InvalidArgument(parameter, fmt::format("must be a number, got {}", j.dump()));
    return j.get<double>();
}

int integer(const json& j, const std::string& parameter) {
    if (!j.is_number_integer())
        throw InvalidArgument(parameter, fmt::format("must be an integer, got {}", j.dump()));
    const auto v = j.get<long long>();
    if (v < -(1LL << 31) || v >= (1LL << 31))
        throw InvalidArgument(parameter, fmt::format("is out of range, got {}", v));
    return int(v);
}

std::string string(const json& j, const std::string& parameter) {
    if (!j.is_string())
        throw InvalidArgument(parameter, fmt::format("must be a string, got {}", j.dump()));
    return j.get<std::string>();
}

glm::dvec3 vec3(const json& j, const std::string& parameter) {
    if (!j.is_array() || j.size() != 3)
        throw InvalidArgument(parameter, "must be an array of 3 numbers [x, y, z] (Z up)");
    return {number(j[0], parameter + "[0]"), number(j[1], parameter + "[1]"),
            number(j[2], parameter + "[2]")};
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
    check_keys(j, "camera", {"matrix_world", "type", "lens_mm", "sensor_width_mm",
                             "sensor_height_mm", "sensor_fit", "fov_deg", "ortho_scale",
                             "panorama_type", "latitude_min_deg", "latitude_max_deg",
                             "longitude_min_deg", "longitude_max_deg", "shift_x", "shift_y",
                             "clip_start_m", "clip_end_m"});
    Camera c;
    if (!j.contains("matrix_world"))
        throw InvalidArgument("camera.matrix_world",
                              "is required: Blender's Object.matrix_world, 4 rows of 4 numbers");
    const json& m = j["matrix_world"];
    if (!m.is_array() || m.size() != 4)
        throw InvalidArgument("camera.matrix_world", "must be 4 rows of 4 numbers (Blender's "
                                                     "Object.matrix_world, by rows)");
    for (int r = 0; r < 4; ++r) {
        const std::string pr = fmt::format("camera.matrix_world[{}]", r);
        if (!m[r].is_array() || m[r].size() != 4)
            throw InvalidArgument(pr, "must be a row of 4 numbers");
        for (int col = 0; col < 4; ++col)
            c.matrix_world[col][r] = number(m[r][col], fmt::format("{}[{}]", pr, col));
    }
    if (!j.contains("type"))
        throw InvalidArgument("camera.type", "is required: \"PERSP\", \"ORTHO\" or \"PANO\"");
    c.type = camera_type_from_name(string(j["type"], "camera.type"), "camera.type");
    if (j.contains("fov_deg") && j.contains("lens_mm"))
        throw InvalidArgument("camera.fov_deg", "give either lens_mm or fov_deg, not both");
    if (j.contains("lens_mm")) c.lens_mm = number(j["lens_mm"], "camera.lens_mm");
    if (j.contains("fov_deg")) {
        c.fov_rad = number(j["fov_deg"], "camera.fov_deg") * kDegree;
        if (!(c.fov_rad > 0.0))
            throw InvalidArgument("camera.fov_deg", "must be in (0, 179.9] degrees");
    }
    if (j.contains("sensor_width_mm")) c.sensor_width_mm = number(j["sensor_width_mm"], "camera.sensor_width_mm");
    if (j.contains("sensor_height_mm")) c.sensor_height_mm = number(j["sensor_height_mm"], "camera.sensor_height_mm");
    if (j.contains("sensor_fit"))
        c.sensor_fit = sensor_fit_from_name(string(j["sensor_fit"], "camera.sensor_fit"), "camera.sensor_fit");
    if (j.contains("ortho_scale")) c.ortho_scale = number(j["ortho_scale"], "camera.ortho_scale");
    if (j.contains("panorama_type")) {
        const std::string t = string(j["panorama_type"], "camera.panorama_type");
        if (t != "EQUIRECTANGULAR")
            throw InvalidArgument("camera.panorama_type",
                                  fmt::format("only \"EQUIRECTANGULAR\" is supported, got \"{}\" "
                                              "(fisheye and mirror-ball panoramas are not)", t));
    }
    // Blender keeps these in float32 radians: -pi/2 comes out as -90.0000025 degrees.
    // Values within 1e-3 degrees beyond the range are taken as its end.
    const auto angle = [&](const char* key, double limit_deg, double& out) {
        if (!j.contains(key)) return;
        double deg = number(j[key], std::string("camera.") + key);
        if (std::abs(deg) > limit_deg && std::abs(deg) < limit_deg + 1e-3) deg = std::copysign(limit_deg, deg);
        out = deg * kDegree;
    };
    angle("latitude_min_deg", 90.0, c.latitude_min_rad);
    angle("latitude_max_deg", 90.0, c.latitude_max_rad);
    angle("longitude_min_deg", 180.0, c.longitude_min_rad);
    angle("longitude_max_deg", 180.0, c.longitude_max_rad);
    if (j.contains("shift_x")) c.shift_x = number(j["shift_x"], "camera.shift_x");
    if (j.contains("shift_y")) c.shift_y = number(j["shift_y"], "camera.shift_y");
    if (j.contains("clip_start_m")) c.clip_start_m = number(j["clip_start_m"], "camera.clip_start_m");
    if (j.contains("clip_end_m")) c.clip_end_m = number(j["clip_end_m"], "camera.clip_end_m");
    c.validate("camera");
    return c;
}

SceneDescription parse(const json& j) {
    check_keys(j, "", {"version", "atmosphere", "origin_altitude_m", "sun", "exposure", "method",
                       "camera", "resolution", "aerial", "sky_options", "$schema", "comment"});
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
        s.origin_altitude_m = number(j["origin_altitude_m"], "origin_altitude_m");
    if (j.contains("sun")) {
        const json& sun = j["sun"];
        check_keys(sun, "sun", {"direction", "elevation_deg", "azimuth_deg"});
        const bool by_angles = sun.contains("elevation_deg") || sun.contains("azimuth_deg");
        if (sun.contains("direction") == by_angles)
            throw InvalidArgument("sun", "give either \"direction\" [x, y, z] or "
                                         "\"elevation_deg\" and \"azimuth_deg\"");
        if (by_angles) {
            if (!sun.contains("elevation_deg") || !sun.contains("azimuth_deg"))
                throw InvalidArgument("sun", "needs both \"elevation_deg\" and \"azimuth_deg\"");
            s.sun_direction = sun_direction_from_angles_deg(number(sun["elevation_deg"], "sun.elevation_deg"),
                                                            number(sun["azimuth_deg"], "sun.azimuth_deg"));
        } else {
            s.sun_direction = vec3(sun["direction"], "sun.direction");
        }
    }
    if (j.contains("exposure")) s.exposure = number(j["exposure"], "exposure");
    if (j.contains("method")) s.method = string(j["method"], "method");
    if (j.contains("camera") && !j["camera"].is_null()) s.camera = parse_camera(j["camera"]);
    if (j.contains("resolution")) {
        const json& r = j["resolution"];
        check_keys(r, "resolution", {"x", "y", "percentage"});
        if (r.contains("x")) s.resolution.x = integer(r["x"], "resolution.x");
        if (r.contains("y")) s.resolution.y = integer(r["y"], "resolution.y");
        if (r.contains("percentage")) s.resolution.percentage = integer(r["percentage"], "resolution.percentage");
    }
    if (j.contains("aerial")) {
        const json& a = j["aerial"];
        check_keys(a, "aerial", {"method", "froxels", "max_depth_m", "steps_per_slice",
                                 "raymarch_steps", "sky_depth_m"});
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
        if (a.contains("max_depth_m")) o.max_depth_m = number(a["max_depth_m"], "aerial.max_depth_m");
        if (a.contains("steps_per_slice")) o.steps_per_slice = integer(a["steps_per_slice"], "aerial.steps_per_slice");
        if (a.contains("raymarch_steps")) o.raymarch_steps = integer(a["raymarch_steps"], "aerial.raymarch_steps");
        if (a.contains("sky_depth_m")) o.sky_depth_m = number(a["sky_depth_m"], "aerial.sky_depth_m");
    }
    if (j.contains("sky_options")) {
        const json& o = j["sky_options"];
        check_keys(o, "sky_options", {"transmittance_width", "transmittance_height",
                                      "multiscattering_size", "skyview_width", "skyview_height",
                                      "raymarch_steps", "raymarch_sun_steps", "reference_paths",
                                      "seed"});
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
    s.validate();
    return s;
}

}  // namespace

SceneDescription SceneDescription::from_json_string(const std::string& text) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InvalidArgument("scene JSON", fmt::format("malformed at byte {}: {}", e.byte, e.what()));
    }
    return parse(j);
}

SceneDescription SceneDescription::from_json_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw IoError(fmt::format("cannot read scene file '{}'", path));
    std::stringstream ss;
    ss << in.rdbuf();
    return from_json_string(ss.str());
}

std::string SceneDescription::to_json_string() const {
    validate();
    ordered_json j;
    j["version"] = version;
    j["atmosphere"] = ordered_json::parse(atmosphere.to_json_string());
    j["origin_altitude_m"] = origin_altitude_m;
    j["sun"] = {{"direction", {sun_direction.x, sun_direction.y, sun_direction.z}}};
    j["exposure"] = exposure;
    j["method"] = method;
    if (camera) {
        const Camera& c = *camera;
        ordered_json cj;
        ordered_json rows = ordered_json::array();
        for (int r = 0; r < 4; ++r)
            rows.push_back({c.matrix_world[0][r], c.matrix_world[1][r], c.matrix_world[2][r],
                            c.matrix_world[3][r]});
        cj["matrix_world"] = rows;
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
    return j.dump(2);
}

void SceneDescription::to_json_file(const std::string& path, bool overwrite) const {
    namespace fs = std::filesystem;
    const std::string text = to_json_string() + "\n";
    const fs::path target = fs::absolute(fs::path(path));
    std::error_code ec;
    if (!overwrite && fs::exists(target, ec))
        throw IoError(fmt::format("'{}' exists; refusing to overwrite it", path));
    // Written beside the target and moved into place: never a half-written file.
    const fs::path tmp = target.parent_path() / ("." + target.filename().string() + ".welkin-tmp");
    {
        std::ofstream out(tmp);
        if (!out) throw IoError(fmt::format("cannot write '{}'", path));
        out << text;
        if (!out.flush()) {
            out.close();
            fs::remove(tmp, ec);
            throw IoError(fmt::format("cannot write '{}'", path));
        }
    }
    fs::rename(tmp, target, ec);
    if (ec) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        throw IoError(fmt::format("cannot write '{}': {}", path, ec.message()));
    }
}

}  // namespace welkin
