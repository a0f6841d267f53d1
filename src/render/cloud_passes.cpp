// SPDX-License-Identifier: Apache-2.0
// Camera cloud passes; see cloud_passes.hpp.
#include "welkin/render/cloud_passes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/base/camera.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/memory.hpp"
#include "welkin/clouds/illumination.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/color/color.hpp"

namespace welkin {

CloudPasses render_cloud_passes(const SceneDescription& scene, const CloudDensity& density,
                                std::span<const float> depth, Progress* progress, RowRange rows_in) {
    scene.validate();
    const Camera& camera = scene.require_camera();
    const int w = scene.resolution.width(), h = scene.resolution.height();
    const std::size_t nc = scene.atmosphere.channels();
    // Besides the aerial passes' own buffers: rays (origin, direction, length: 56 bytes),
    // the march's radiance, transmittance and depth, the RGB and the passes (40 bytes).
    check_frame_memory(w, h, kAerialPassBytesPerPixel + 96 + 4 * nc, "aerial and cloud passes");
    if (!depth.empty()) validate_depth(depth, w, h);
    CloudLightingOptions options = scene.clouds ? scene.clouds->lighting : CloudLightingOptions{};
    const RowRange band = rows_in.resolved(h);
    // The band's pixels q0 + q, q in [0, n).
    const std::size_t q0 = std::size_t(band.begin) * std::size_t(w);
    const std::size_t n = std::size_t(band.size()) * std::size_t(w);

    // Each pixel's centre ray, ending at the geometry (or at max_distance_m).
    const CameraRays rays(camera, w, h);
    std::vector<glm::dvec3> origins(n), dirs(n);
    std::vector<double> lengths(n), per_depth(n);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    tbb::parallel_for(tbb::blocked_range<int>(band.begin, band.end), [&](const auto& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const std::size_t q = std::size_t(j - band.begin) * std::size_t(w) + std::size_t(i);
                const CameraRays::Ray ray = rays.at_pixel(i, j);
                origins[q] = ray.origin;
                dirs[q] = ray.direction;
                per_depth[q] = ray.distance_per_depth;
                const float z = depth.empty() ? std::numeric_limits<float>::infinity() : depth[q0 + q];
                lengths[q] =
                    is_sky_depth(z, scene.aerial.sky_depth_m) ? kInf : double(z) * ray.distance_per_depth;
            }
    });
    // The rays' footprint (lighting.hpp), unless the scene sets it: the angle and the
    // distance between the middle pixel's ray and its right-hand neighbour's (a perspective
    // or panoramic camera's rays diverge, an orthographic camera's are a pixel apart).
    if (options.ray_spread_rad == 0.0 && options.ray_width_m == 0.0 && w >= 2) {
        const CameraRays::Ray a = rays.at_pixel(w / 2 - 1, h / 2), b = rays.at_pixel(w / 2, h / 2);
        options.ray_spread_rad = std::min(1.0, angle_between_rays(a.direction, b.direction));
        options.ray_width_m = std::min(1e6, glm::length(a.origin - b.origin));
    }
    ProgressStage lut_stage(progress, 0.0, 0.05);
    if (!lut_stage.report(0.0)) throw Cancelled();
    const AtmosphereIllumination light(scene.atmosphere, scene.origin_observer(), scene.sky_options.luts());
    if (!lut_stage.report(1.0)) throw Cancelled();

    ProgressStage march_stage(progress, 0.05, 0.9);
    CloudResult march = render_clouds(density, light, origins, dirs, lengths, options, &march_stage, q0);
    lengths = {};

    // Cloud radiance to the scene's RGB (the sky's conversion).
    CloudPasses out;
    out.width = w;
    out.height = band.size();
    out.row_begin = band.begin;
    out.clouds.assign(n * 4, 0.0f);
    out.depth.assign(n, kNoCloudDepth);
    std::vector<float> rgb(n * 3);
    SpectrumToRgb(scene.atmosphere.wavelengths_nm, -3.0, scene.color_space).convert(march.radiance, rgb);
    march.radiance = {};

    // The air in front of each cloud, marched per pixel to its cloud depth d_c (header;
    // the shared march of aerial_along_rays, as the equirect sky's clouds get it).
    ProgressStage air_stage(progress, 0.9, 1.0);
    if (!air_stage.report(0.0)) throw Cancelled();
    // 0: no cloud, or a cloud at a sky depth (>= aerial.sky_depth_m), as the aerial
    // passes treat it: not marched, T = 1, S = 0.
    std::vector<double> cloud_d(n, 0.0);
    for (std::size_t q = 0; q < n; ++q)
        if (march.transmittance[q] < 1.0f &&
            !is_sky_depth(float(double(march.depth_m[q]) / per_depth[q]), scene.aerial.sky_depth_m))
            cloud_d[q] = double(march.depth_m[q]);
    const AirAlongRays air = aerial_along_rays(
        scene.atmosphere, light.luts(), scene.planet_centre(), scene.origin_observer().sun_direction, origins,
        dirs, cloud_d, scene.aerial.raymarch_steps, scene.exposure, false, scene.color_space);
    origins = {};
    dirs = {};
    const float exposure = float(scene.exposure);
    for (std::size_t q = 0; q < n; ++q) {
        if (!(march.transmittance[q] < 1.0f)) continue;
        const float alpha = 1.0f - march.transmittance[q];
        for (int c = 0; c < 3; ++c)
            out.clouds[q * 4 + c] =
                air.transmittance[q * 3 + c] * rgb[q * 3 + c] * exposure + alpha * air.inscatter[q * 3 + c];
        out.clouds[q * 4 + 3] = alpha;
        out.depth[q] = float(double(march.depth_m[q]) / per_depth[q]);
    }
    if (progress && !progress->report(1.0)) throw Cancelled();
    return out;
}

CloudPasses render_cloud_passes(const SceneDescription& scene, std::span<const float> depth,
                                Progress* progress, RowRange rows) {
    scene.validate();
    if (!scene.has_clouds())
        throw InvalidArgument("clouds",
                              "the scene has no cloud layers or volumes (its \"clouds\" key is "
                              "absent or empty)");
    const auto density = scene.cloud_density();
    return render_cloud_passes(scene, *density, depth, progress, rows);
}

}  // namespace welkin
