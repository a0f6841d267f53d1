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

// The frame-wide part (header): the checks, the resolved upsampling, the atmosphere's light
// and the shared CloudLighting (its options with the rays' footprint).
struct CloudPassRenderer::Impl {
    Impl(const SceneDescription& s, const CloudDensity& d)
        : scene(s),
          w(scene.resolution.width()),
          h(scene.resolution.height()),
          rays(scene.require_camera(), w, h),
          upsampling(resolved_upsampling(scene)),
          light(scene.atmosphere, scene.origin_observer(), scene.sky_options.luts()),
          lighting(d, light, footprint_options(scene, rays)) {}

    // Besides the aerial passes' own buffers: rays (origin, direction, length: 56 bytes),
    // the march's radiance, transmittance and depth, the RGB and the passes (40 bytes).
    static const SceneDescription& checked(const SceneDescription& s) {
        s.validate();
        s.require_camera();
        check_frame_memory(s.resolution.width(), s.resolution.height(),
                           kAerialPassBytesPerPixel + 96 + 4 * s.atmosphere.channels(),
                           "aerial and cloud passes");
        return s;
    }

    // The scene's lighting options; the rays' footprint (lighting.hpp), unless the scene sets
    // it: the angle and the distance between the middle pixel's ray and its right-hand
    // neighbour's (a perspective or panoramic camera's rays diverge, an orthographic
    // camera's are a pixel apart).
    static CloudLightingOptions footprint_options(const SceneDescription& scene, const CameraRays& rays) {
        CloudLightingOptions o = scene.clouds ? scene.clouds->lighting : CloudLightingOptions{};
        const int w = scene.resolution.width(), h = scene.resolution.height();
        if (o.ray_spread_rad == 0.0 && o.ray_width_m == 0.0 && w >= 2) {
            const CameraRays::Ray a = rays.at_pixel(w / 2 - 1, h / 2), b = rays.at_pixel(w / 2, h / 2);
            o.ray_spread_rad = std::min(1.0, angle_between_rays(a.direction, b.direction));
            o.ray_width_m = std::min(1e6, glm::length(a.origin - b.origin));
        }
        return o;
    }

    static CloudUpsampling resolved_upsampling(const SceneDescription& scene) {
        CloudUpsampling u = scene.clouds ? scene.clouds->upsampling : CloudUpsampling{};
        u.validate();
        u.stride = u.resolved_stride(scene.resolution.width(), scene.resolution.height());
        return u;
    }

    const SceneDescription& scene;
    int w, h;
    CameraRays rays;
    CloudUpsampling upsampling;
    AtmosphereIllumination light;
    CloudLighting lighting;
};

CloudPassRenderer::CloudPassRenderer(const SceneDescription& scene, const CloudDensity& density)
    : impl_(std::make_unique<Impl>(Impl::checked(scene), density)) {}
CloudPassRenderer::~CloudPassRenderer() = default;

CloudPasses CloudPassRenderer::render(std::span<const float> depth, Progress* progress,
                                      RowRange rows_in) const {
    const Impl& f = *impl_;
    const SceneDescription& scene = f.scene;
    const int w = f.w, h = f.h;
    if (!depth.empty()) validate_depth(depth, w, h);
    const RowRange band = rows_in.resolved(h);
    // The band's pixels q0 + q, q in [0, n).
    const std::size_t q0 = std::size_t(band.begin) * std::size_t(w);
    const std::size_t n = std::size_t(band.size()) * std::size_t(w);
    // The marched rows: the band widened to every block of the upsampling lattice (rows 0,
    // s, 2s, ... of the frame, and its last) whose closed rectangle holds a row of the band,
    // blocks k s .. (k + 1) s for k from ceil(begin / s) - 1 to floor((end - 1) / s). A
    // block's refinement depends on its own rays alone, and a pixel on a block's edge is
    // marched when either block beside it splits there; so with every such block whole the
    // band gets the frame's values (lighting.hpp, render_clouds_grid).
    const int s = f.upsampling.stride;
    const int k_first = std::max(0, (band.begin + s - 1) / s - 1), k_last = (band.end - 1) / s;
    const RowRange marched{k_first * s, std::min(h, (k_last + 1) * s + 1)};
    const std::size_t m0 = std::size_t(marched.begin) * std::size_t(w);
    const std::size_t m = std::size_t(marched.size()) * std::size_t(w);

    // Each pixel's centre ray, ending at the geometry (or at max_distance_m).
    const CameraRays& rays = f.rays;
    std::vector<glm::dvec3> origins(m), dirs(m);
    std::vector<double> lengths(m), per_depth(m);
    constexpr double kInf = std::numeric_limits<double>::infinity();
    tbb::parallel_for(tbb::blocked_range<int>(marched.begin, marched.end), [&](const auto& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const std::size_t q = std::size_t(j - marched.begin) * std::size_t(w) + std::size_t(i);
                const CameraRays::Ray ray = rays.at_pixel(i, j);
                origins[q] = ray.origin;
                dirs[q] = ray.direction;
                per_depth[q] = ray.distance_per_depth;
                const float z = depth.empty() ? std::numeric_limits<float>::infinity() : depth[m0 + q];
                lengths[q] =
                    is_sky_depth(z, scene.aerial.sky_depth_m) ? kInf : double(z) * ray.distance_per_depth;
            }
    });
    ProgressStage lut_stage(progress, 0.0, 0.05);
    if (!lut_stage.report(1.0)) throw Cancelled();
    ProgressStage march_stage(progress, 0.05, 0.9);
    CloudResult march =
        render_clouds_grid(f.lighting, origins, dirs, lengths, w, f.upsampling, &march_stage, m0);
    lengths = {};
    const CloudGridInterpolation& grid = march.interpolation;

    // Cloud radiance to the scene's RGB (the sky's conversion).
    std::vector<float> rgb(m * 3);
    SpectrumToRgb(scene.atmosphere.wavelengths_nm, -3.0, scene.color_space).convert(march.radiance, rgb);
    march.radiance = {};

    // The air in front of each marched ray's cloud, marched to its cloud depth d_c (header;
    // the shared march of aerial_along_rays, as the equirect sky's clouds get it); the
    // interpolated rays get the whole pass interpolated from their block's corners, as the
    // equirect sky's do (sky_image.hpp).
    ProgressStage air_stage(progress, 0.9, 1.0);
    if (!air_stage.report(0.0)) throw Cancelled();
    // 0: no cloud, a cloud at a sky depth (>= aerial.sky_depth_m), as the aerial passes
    // treat it (T = 1, S = 0), or an interpolated ray: not marched.
    std::vector<double> cloud_d(m, 0.0);
    for (std::size_t q = 0; q < m; ++q)
        if (grid.was_marched(q) && march.transmittance[q] < 1.0f &&
            !is_sky_depth(float(double(march.depth_m[q]) / per_depth[q]), scene.aerial.sky_depth_m))
            cloud_d[q] = double(march.depth_m[q]);
    const AirAlongRays air = aerial_along_rays(
        scene.atmosphere, f.light.luts(), scene.planet_centre(), scene.origin_observer().sun_direction,
        origins, dirs, cloud_d, scene.aerial.raymarch_steps, scene.exposure, false, scene.color_space);
    origins = {};
    dirs = {};
    cloud_d = {};
    const float exposure = float(scene.exposure);
    std::vector<float> clouds(m * 4, 0.0f);
    for (std::size_t q = 0; q < m; ++q) {
        if (!grid.was_marched(q) || !(march.transmittance[q] < 1.0f)) continue;
        const float alpha = 1.0f - march.transmittance[q];
        for (int c = 0; c < 3; ++c)
            clouds[q * 4 + c] =
                air.transmittance[q * 3 + c] * rgb[q * 3 + c] * exposure + alpha * air.inscatter[q * 3 + c];
        clouds[q * 4 + 3] = alpha;
    }
    grid.interpolate(clouds, 4);

    // The band's rows of the marched ones.
    CloudPasses out;
    out.width = w;
    out.height = band.size();
    out.row_begin = band.begin;
    out.clouds.assign(n * 4, 0.0f);
    out.depth.assign(n, kNoCloudDepth);
    const std::size_t skip = q0 - m0;
    for (std::size_t q = 0; q < n; ++q) {
        const std::size_t r = skip + q;
        if (!(march.transmittance[r] < 1.0f)) continue;
        for (int c = 0; c < 4; ++c) out.clouds[q * 4 + c] = clouds[r * 4 + c];
        out.depth[q] = float(double(march.depth_m[r]) / per_depth[r]);
    }
    if (progress && !progress->report(1.0)) throw Cancelled();
    return out;
}

CloudPasses render_cloud_passes(const SceneDescription& scene, const CloudDensity& density,
                                std::span<const float> depth, Progress* progress, RowRange rows) {
    ProgressStage frame_stage(progress, 0.0, 0.05);
    if (!frame_stage.report(0.0)) throw Cancelled();
    const CloudPassRenderer renderer(scene, density);
    return renderer.render(depth, progress, rows);
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
