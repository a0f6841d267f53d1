// SPDX-License-Identifier: Apache-2.0
// A scene's clouds; see scene/clouds.hpp.
#include "welkin/scene/clouds.hpp"

#include <fmt/format.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/union.hpp"

namespace welkin {
namespace {

// The core's message without its own "parameter: " prefix.
std::string reason(const InvalidArgument& e) {
    const std::string what = e.what(), own = e.parameter() + ": ";
    return what.rfind(own, 0) == 0 ? what.substr(own.size()) : what;
}

template <class F>
void prefixed(const std::string& prefix, F&& f) {
    try {
        f();
    } catch (const InvalidArgument& e) {
        throw InvalidArgument(prefix + e.parameter(), reason(e));
    }
}

}  // namespace

const char* vdb_negative_name(VdbCloudOptions::Negative negative) {
    return negative == VdbCloudOptions::Negative::Clamp ? "clamp" : "reject";
}

VdbCloudOptions::Negative vdb_negative_from_name(const std::string& name, const std::string& parameter) {
    if (name == "clamp") return VdbCloudOptions::Negative::Clamp;
    if (name == "reject") return VdbCloudOptions::Negative::Reject;
    throw InvalidArgument(parameter, fmt::format("must be \"clamp\" or \"reject\", got \"{}\"", name));
}

const char* vdb_placement_name(VdbCloudOptions::VoxelPlacement placement) {
    return placement == VdbCloudOptions::VoxelPlacement::Blender ? "blender" : "openvdb";
}

VdbCloudOptions::VoxelPlacement vdb_placement_from_name(const std::string& name,
                                                        const std::string& parameter) {
    if (name == "blender") return VdbCloudOptions::VoxelPlacement::Blender;
    if (name == "openvdb") return VdbCloudOptions::VoxelPlacement::OpenVdb;
    throw InvalidArgument(parameter, fmt::format("must be \"blender\" or \"openvdb\", got \"{}\"", name));
}

CloudLayerParams scene_cloud_layer(const CloudLayerParams& layer, double planet_radius_m,
                                   double origin_altitude_m) {
    CloudLayerParams p = layer;
    p.planet_radius_m = planet_radius_m;
    p.origin_altitude_m = origin_altitude_m;
    return p;
}

void SceneClouds::validate(double planet_radius_m, double origin_altitude_m) const {
    if (layers.size() > kMaxLayers)
        throw InvalidArgument("clouds.layers",
                              fmt::format("must have at most {} layers, got {}", kMaxLayers, layers.size()));
    if (volumes.size() > kMaxVolumes)
        throw InvalidArgument("clouds.volumes", fmt::format("must have at most {} volumes, got {}",
                                                            kMaxVolumes, volumes.size()));
    for (std::size_t i = 0; i < layers.size(); ++i)
        prefixed(fmt::format("clouds.layers[{}].", i),
                 [&] { scene_cloud_layer(layers[i], planet_radius_m, origin_altitude_m).validate(); });
    for (std::size_t i = 0; i < volumes.size(); ++i) {
        const SceneCloudVolume& v = volumes[i];
        const std::string p = fmt::format("clouds.volumes[{}].", i);
        if (v.file.empty())
            throw InvalidArgument(p + "file", "is required: the volume's .vdb file for this frame");
        if (v.options.grid.empty())
            throw InvalidArgument(p + "grid", "must name a grid (Blender's default: \"density\")");
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r)
                require_finite(fmt::format("{}matrix_world[{}][{}]", p, r, c), v.options.matrix_world[c][r]);
        require_in_range(p + "density_scale", v.options.density_scale, 0.0, 1e6, "m^-1 per unit grid value");
    }
    prefixed("clouds.scattering.", [&] { lighting.scattering.validate(); });
    CloudLightingOptions rest = lighting;
    rest.scattering = {};
    prefixed("clouds.lighting.", [&] { rest.validate(); });
    prefixed("clouds.upsampling.", [&] { upsampling.validate(); });
}

std::shared_ptr<const CloudDensity> make_scene_cloud_density(const SceneClouds& clouds,
                                                             double planet_radius_m,
                                                             double origin_altitude_m) {
    clouds.validate(planet_radius_m, origin_altitude_m);
    if (clouds.empty()) return nullptr;
    std::vector<std::shared_ptr<const CloudDensity>> sources;
    for (const CloudLayerParams& layer : clouds.layers)
        sources.push_back(
            std::make_shared<ProceduralClouds>(scene_cloud_layer(layer, planet_radius_m, origin_altitude_m)));
    for (std::size_t i = 0; i < clouds.volumes.size(); ++i) {
        const SceneCloudVolume& v = clouds.volumes[i];
        const std::string parameter = fmt::format("clouds.volumes[{}].file", i);
        const std::string object = v.name.empty() ? std::string() : fmt::format(" (object \"{}\")", v.name);
        // VdbClouds' messages name the file and the grid; the path is added if one does not.
        const auto message = [&](const std::string& what) {
            return what.find(v.file) == std::string::npos ? fmt::format("'{}'{}: {}", v.file, object, what)
                                                          : fmt::format("{}{}", what, object);
        };
        try {
            sources.push_back(std::make_shared<VdbClouds>(v.file, v.options));
        } catch (const InvalidArgument& e) {
            throw InvalidArgument(parameter, message(e.what()));
        } catch (const IoError& e) {
            throw InvalidArgument(parameter, message(e.what()));
        }
    }
    if (sources.size() == 1) return sources.front();
    return std::make_shared<CloudUnion>(std::move(sources));
}

}  // namespace welkin
