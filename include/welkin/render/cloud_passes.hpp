// SPDX-License-Identifier: Apache-2.0
// Camera cloud passes: what the scene camera sees of the scene's clouds, in front of the
// scene's geometry, with the air between the camera and the cloud (docs/design.md pass names;
// docs/pipelines.md "Clouds in a scene" gives the same definition).
//
// For every pixel of the scene's render (scene.resolution, camera.hpp's rays: perspective,
// orthographic and equirectangular panoramas) the pixel's centre ray goes through the
// clouds' density (clouds/lighting.hpp, the scene's clouds.lighting options, lit by the
// atmosphere: AtmosphereIllumination with the observer at the scene origin, as the sky
// image's clouds are). The ray ends at the scene's geometry: the Z pass `depth` (Blender's
// convention, camera.hpp), converted to a distance along the ray by the ray's
// distance_per_depth; sky pixels (depth +inf or >= aerial.sky_depth_m) and a render
// without a depth image run to clouds.lighting.max_distance_m. Geometry in front of a cloud
// therefore hides it. The rays are upsampled as the equirect sky's are (the scene's
// clouds.upsampling; render_clouds_grid with the rays' lengths): a lattice of marched
// rays refined where the clouds have edges, the rest interpolated, never across the
// geometry's silhouettes; stride 1 marches every pixel.
//
// The march gives, per pixel, the cloud's in-scattered radiance L_c (premultiplied), its
// transmittance T_c, and the transmittance-weighted depth d_c of its scattering. The air in
// front of the cloud is then applied. Along the ray, with the air's in-scattering S(a, b)
// and transmittance T(a, b) between distances a and b, a cloud taken at d_c in front of a
// surface at d_s of radiance I:
//     L = S(0, d_c) + T(0, d_c) [L_c + T_c (S(d_c, d_s) + T(d_c, d_s) I)].
// Since S(0, d_s) = S(0, d_c) + T(0, d_c) S(d_c, d_s) and T(0, d_s) = T(0, d_c) T(d_c, d_s),
//     L = [T(0, d_c) L_c + (1 - T_c) S(0, d_c)] + T_c [S(0, d_s) + T(0, d_s) I],
// which is the compositor's "over" of the premultiplied pass
//     Welkin.Clouds.rgb = T(0, d_c) L_c + (1 - T_c) S(0, d_c),   Welkin.Clouds.a = 1 - T_c
// on the hazed render Image x AerialTransmittance + AerialInscatter:
//     final = Clouds.rgb + (1 - Clouds.a) (Image x AerialTransmittance + AerialInscatter).
// Over a sky pixel (T = 1, S = 0 in the aerial passes, the rendered sky holding the air's
// whole path radiance) the same formula is exact as well: the sky is S(0, d_c) +
// T(0, d_c) S(d_c, inf).
//
// The air terms T(0, d_c) and S(0, d_c) are marched per marched ray, from the camera to
// its cloud depth (aerial_along_rays, aerial_perspective.hpp: the per-pixel march of the
// aerial passes' reference method, aerial.raymarch_steps steps; the equirect sky's clouds
// get their air from the same function, sky_image.hpp), not read from a froxel volume.
// Why: (1) clouds lie kilometres to hundreds of kilometres away, where the froxel volume's
// quadratic slices are coarsest, and its depth range would have to be fitted to the cloud
// depths, which are known only after the cloud march; (2) a ray's air then depends on its
// own cloud depth alone, so a band of rows (the render engine's tiles, `rows`; its clouds
// marched on the frame's lattice, widened to the lattice's blocks around it) has exactly
// the whole frame's values; (3) it is cheap next to the cloud march (64 steps of LUT
// lookups against ~100 steps each with ~12 density samples), and only rays with cloud are
// marched. An interpolated ray gets the whole pass (Welkin.Clouds) interpolated from its
// block's corners, as the equirect sky's do. tests/cpp/test_cloud_passes.cpp checks the
// march against the froxel volume sampled at the same cloud depths (AirInFront...). The
// cloud's depth extent is collapsed to d_c: the air between parts of one cloud is left out
// (a few hundred metres of air inside a cloud several km away).
//
// Colour and units: the cloud radiance is converted to linear Rec.709 as the sky is
// (color.hpp, lambda power -3; the same conversion the equirect sky applies to its clouds),
// W m^-2 sr^-1, times the scene's exposure. (The equirect sky, sky_image.hpp, applies the
// same air in front of its clouds, so a panoramic camera's passes composited over the clear
// HDRI give the cloudy HDRI.) A cloud at a sky depth (d_c / distance_per_depth >=
// aerial.sky_depth_m) gets no air, as the aerial passes treat such depths.
// The air's RGB transmittance multiplies the RGB cloud radiance (as the compositor does for
// surfaces). Welkin.CloudDepth is d_c in Blender's Z convention (along the view axis for
// perspective and orthographic cameras, along the ray for panoramas), kNoCloudDepth (1e10,
// what Cycles writes for the background) where the pixel has no cloud (T_c = 1).
//
// Threads: TBB; results do not depend on the thread count (each pixel's ray is seeded by
// its index). Cancellable through Progress (Cancelled).
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "welkin/base/progress.hpp"
#include "welkin/base/row_range.hpp"
#include "welkin/clouds/density.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin {

inline constexpr float kNoCloudDepth = 1e10f;

struct CloudPasses {
    int width = 0, height = 0;  // of the arrays: the band's rows
    int row_begin = 0;          // the band's first row in the frame
    std::vector<float> clouds;  // (height, width, 4): premultiplied RGBA, top row first
    std::vector<float> depth;   // (height, width): Welkin.CloudDepth
};

// The passes of `density` (lit with scene.clouds' lighting options, or the defaults when
// the scene has no "clouds"). `depth`: empty (no geometry) or the whole frame's
// (height, width) Z pass at the scene's resolution. `rows`: only those rows are computed
// and returned, with the whole frame's values (every ray is seeded by its pixel's index in
// the frame). Throws InvalidArgument naming "camera" (none), "depth", "resolution" or
// "rows"; Cancelled.
CloudPasses render_cloud_passes(const SceneDescription& scene, const CloudDensity& density,
                                std::span<const float> depth = {}, Progress* progress = nullptr,
                                RowRange rows = {});

// The frame-wide part of the passes, once for a frame whose bands are rendered one by one
// (the render engine's tiles, camera_plate.hpp's CameraPlateRenderer): the checks, the
// atmosphere's light and the clouds' shared lighting (lighting.hpp, CloudLighting), whose
// shadow grids the bands fill and share. render() gives render_cloud_passes's passes for
// `rows`, with the whole frame's values. Keeps references to the scene and the density:
// they must outlive it. render() may run from several threads at once. Throws as
// render_cloud_passes does (the constructor: "camera", "resolution" and the options).
class CloudPassRenderer {
public:
    CloudPassRenderer(const SceneDescription& scene, const CloudDensity& density);
    ~CloudPassRenderer();
    CloudPassRenderer(const CloudPassRenderer&) = delete;
    CloudPassRenderer& operator=(const CloudPassRenderer&) = delete;
    CloudPasses render(std::span<const float> depth = {}, Progress* progress = nullptr,
                       RowRange rows = {}) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The scene's own clouds (scene.cloud_density(): opens the VDBs). InvalidArgument naming
// "clouds" when the scene has none, "clouds.volumes[i].file" for a bad volume.
CloudPasses render_cloud_passes(const SceneDescription& scene, std::span<const float> depth = {},
                                Progress* progress = nullptr, RowRange rows = {});

// The composite of the header, for one pixel and channel (tests, and hosts without a
// compositor): clouds_rgb + (1 - alpha) (image x aerial_transmittance + aerial_inscatter).
inline float composite_clouds(float clouds_rgb, float alpha, float image, float aerial_transmittance,
                              float aerial_inscatter) {
    return clouds_rgb + (1.0f - alpha) * (image * aerial_transmittance + aerial_inscatter);
}

}  // namespace welkin
