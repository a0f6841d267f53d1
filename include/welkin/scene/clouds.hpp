// SPDX-License-Identifier: Apache-2.0
// The clouds of a scene, as plain data: procedural layers, OpenVDB volumes and how they are
// lit. Part of the SceneDescription (scene.hpp, key "clouds" of the scene JSON, docs/pipelines.md
// "Scene JSON", the schema the Blender add-on writes).
//
// A scene's clouds are the union of all its layers and volumes: one density,
// sigma_t = the sum of every source's (clouds/union.hpp), lit once. make_scene_cloud_density
// builds it; that is where VDB files are opened (not when the JSON is read, so that a scene
// can be read, checked and rewritten without touching its volumes).
//
// Layers take the planet's radius and the height of the world origin from the scene
// (atmosphere.bottom_radius_m, origin_altitude_m): they are not separate parameters, so a
// layer always sits on the same ground as the air.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "welkin/clouds/density.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/procedural.hpp"
#include "welkin/clouds/vdb.hpp"

namespace welkin {

// One OpenVDB volume: a Blender volume object's file for this frame.
struct SceneCloudVolume {
    std::string name;  // the Blender object's name (for messages); may be empty
    std::string file;  // the .vdb file; relative paths are resolved against the scene file's folder
    // grid, matrix_world (Blender's Object.matrix_world), density_scale, negative.
    VdbCloudOptions options;
};

struct SceneClouds {
    // The most layers and volumes a scene may have (docs/limits.md): every cloud march
    // visits each of them at every step.
    static constexpr std::size_t kMaxLayers = 32;
    static constexpr std::size_t kMaxVolumes = 64;
    // planet_radius_m and origin_altitude_m of each layer are ignored: the scene's are used.
    std::vector<CloudLayerParams> layers;
    std::vector<SceneCloudVolume> volumes;
    CloudLightingOptions lighting;  // lighting.scattering: the JSON's "scattering"
    // How an equirect sky's cloud pass is upsampled (lighting.hpp; camera passes march
    // every ray).
    CloudUpsampling upsampling;

    bool empty() const { return layers.empty() && volumes.empty(); }

    // Throws InvalidArgument naming the key as in the JSON ("clouds.layers[0].coverage",
    // "clouds.lighting.max_steps", "clouds.volumes[1].file"), or "clouds.layers" /
    // "clouds.volumes" for more than kMaxLayers / kMaxVolumes. Opens no file.
    void validate(double planet_radius_m, double origin_altitude_m) const;
};

// Layer i as built for a scene: the scene's planet radius and origin altitude filled in.
CloudLayerParams scene_cloud_layer(const CloudLayerParams& layer, double planet_radius_m,
                                   double origin_altitude_m);

// The union of every layer and volume (nullptr when there are none). A VDB that cannot be
// used (missing, corrupt, no such grid, wrong grid type, empty, too large, negative values
// with "reject") throws InvalidArgument naming "clouds.volumes[i].file" with the file's
// path and VdbClouds' reason; nothing is returned partly built.
std::shared_ptr<const CloudDensity> make_scene_cloud_density(const SceneClouds& clouds,
                                                             double planet_radius_m,
                                                             double origin_altitude_m);

// The scene JSON's "clouds.lighting" object, as text, onto `options`: the keys it has set
// their fields, the others are kept (the scattering is not among them). For hosts that march
// without a scene (welkin.cloud_radiance's `lighting`). Not a JSON object, an unknown key
// or a bad value: InvalidArgument naming it as a scene file would ("clouds.lighting.sides").
// The result is validated (CloudLightingOptions::validate, its parameter prefixed so).
void apply_cloud_lighting_json(const std::string& text, CloudLightingOptions& options);

// "clamp" | "reject" (the JSON's "negative").
const char* vdb_negative_name(VdbCloudOptions::Negative negative);
VdbCloudOptions::Negative vdb_negative_from_name(const std::string& name, const std::string& parameter);
// "blender" | "openvdb" (VdbCloudOptions::VoxelPlacement).
const char* vdb_placement_name(VdbCloudOptions::VoxelPlacement placement);
VdbCloudOptions::VoxelPlacement vdb_placement_from_name(const std::string& name,
                                                        const std::string& parameter);

}  // namespace welkin
