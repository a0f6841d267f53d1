// The camera plate: sky, sun disc and aerial perspective over the ground; see
// camera_plate.hpp.
#include "welkin/camera_plate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/aerial_perspective.hpp"
#include "welkin/auto_sky.hpp"
#include "welkin/cloud_passes.hpp"
#include "welkin/color.hpp"
#include "welkin/error.hpp"
#include "welkin/geometry.hpp"
#include "welkin/math.hpp"
#include "welkin/sky_method.hpp"
#include "welkin/sun.hpp"

namespace welkin {
namespace {

void check(Progress* p, double f) {
    if (p && !p->report(f)) throw Cancelled();
}

double angle_between(const glm::dvec3& a, const glm::dvec3& b) {
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

}  // namespace

CameraPlate render_camera_plate(const SceneDescription& scene, Progress* host_progress, RowRange rows_in) {
    scene.validate();
    const Camera& camera = scene.require_camera();
    const Atmosphere& atm = scene.atmosphere;
    const int w = scene.resolution.width(), h = scene.resolution.height();
    const RowRange band = rows_in.resolved(h);
    const std::size_t q0 = std::size_t(band.begin) * std::size_t(w), q1 = std::size_t(band.end) * std::size_t(w);
    check_aerial_memory(w, h, 18 * sizeof(float));
    // The clouds' density first (a bad VDB is refused before any work), and their march
    // takes most of the time: the sky and the air get the first 30 % of the progress.
    const std::shared_ptr<const CloudDensity> clouds = scene.cloud_density();
    ProgressStage clear_stage(host_progress, 0.0, clouds ? 0.3 : 1.0);
    Progress* progress = host_progress ? &clear_stage : nullptr;
    const CameraRays rays(camera, w, h);
    const glm::dvec3 centre = scene.planet_centre();
    const double R = atm.bottom_radius_m;

    const double cam_r = glm::length(rays.position() - centre);
    if (!(cam_r >= R))
        throw InvalidArgument("camera.matrix_world",
                              fmt::format("puts the camera {:.6g} m below the ground (it must stand "
                                          "at or above altitude 0 m)",
                                          R - cam_r));
    const Observer observer = Observer{cam_r - R, scene.sun_direction}.validated();

    // Depth to the ground sphere per pixel (Z-pass units), +infinity for sky pixels.
    const std::size_t n = std::size_t(w) * std::size_t(h);
    CameraPlate plate;
    plate.width = w;
    plate.height = h;
    plate.depth.assign(n, std::numeric_limits<float>::infinity());
    std::vector<glm::dvec3> dirs(n);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const auto& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const CameraRays::Ray ray = rays.at_pixel(i, j);
                const std::size_t q = std::size_t(j) * std::size_t(w) + std::size_t(i);
                dirs[q] = ray.direction;
                const glm::dvec3 rel = ray.origin - centre;
                const double r = glm::length(rel);
                const double mu = glm::dot(rel, ray.direction) / r;
                if (r > R && ray_hits_ground(r, mu, R))
                    plate.depth[q] = float(distance_to_bottom(r, mu, R) / ray.distance_per_depth);
                else if (r <= R)
                    plate.depth[q] = 0.0f;  // an orthographic ray starting underground
            }
    });
    check(progress, 0.02);

    // Sky radiance for the band's sky pixels, one call.
    std::vector<std::size_t> sky_pixels;
    std::vector<glm::dvec3> sky_dirs;
    for (std::size_t q = q0; q < q1; ++q)
        if (std::isinf(plate.depth[q])) {
            sky_pixels.push_back(q);
            sky_dirs.push_back(dirs[q]);
        }
    // "auto" chooses by the number of directions: choose here for the whole frame's sky
    // pixels, so that a band renders with the method the whole frame would (AutoSky makes
    // the same choice for a whole-frame call).
    std::unique_ptr<SkyMethod> method;
    if (scene.method == "auto") {
        std::size_t frame_sky = 0;
        for (std::size_t q = 0; q < n; ++q) frame_sky += std::isinf(plate.depth[q]) ? 1 : 0;
        const AutoChoice c = choose_sky_method(atm, observer, std::max<std::size_t>(frame_sky, 1), scene.sky_options.tolerance,
                                               scene.sky_options);
        method = make_sky_method(c.method, c.options);
    } else {
        method = make_sky_method(scene.method, scene.sky_options);
    }
    plate.method = method->name();
    const std::size_t nc = atm.channels();
    const SpectrumToRgb sky_to_rgb(atm.wavelengths_nm, -3.0), sun_to_rgb(atm.wavelengths_nm, 0.0);
    plate.sky.assign(n * 3, 0.0f);
    if (!sky_dirs.empty()) {
        ProgressStage stage(progress, 0.02, 0.6);
        const SkyResult sky = sky_radiance(*method, atm, observer, sky_dirs, &stage);
        std::vector<float> rgb(sky_dirs.size() * 3);
        sky_to_rgb.convert(sky.radiance, rgb);
        for (std::size_t k = 0; k < sky_pixels.size(); ++k)
            for (int c = 0; c < 3; ++c) {
                const float v = rgb[k * 3 + c];
                if (!std::isfinite(v))
                    throw std::runtime_error(fmt::format("sky method {} returned a non-finite radiance",
                                                         plate.method));
                plate.sky[sky_pixels[k] * 3 + c] = v * float(scene.exposure);
            }
    }
    check(progress, 0.6);

    // The sun's disc (camera_plate.hpp): mean disc radiance E_sun T / Omega_sun, shaped by
    // the limb darkening, on the samples of the disc above the horizon.
    const SunRadiometry sun = sun_radiometry(atm, observer);
    const double alpha = atm.sun_angular_radius_rad;
    const double omega_sun = kTwoPi * (1.0 - std::cos(alpha));
    const glm::dvec3 s = observer.sun_direction;
    std::vector<LimbDarkening> ld;
    for (double wl : atm.wavelengths_nm) ld.emplace_back(alpha, wl);
    std::vector<double> mean_radiance(nc, 0.0);
    if (sun.visible_fraction > 0.0)
        for (std::size_t c = 0; c < nc; ++c)
            mean_radiance[c] = sun.direct_irradiance[c] / sun.visible_fraction / omega_sun;
    tbb::parallel_for(tbb::blocked_range<int>(band.begin, band.end), [&](const auto& rows) {
        std::vector<float> spectrum(nc);
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const std::size_t q = std::size_t(j) * std::size_t(w) + std::size_t(i);
                if (!std::isinf(plate.depth[q]) || sun.visible_fraction <= 0.0) continue;
                const double sx = (i + 0.5) / w, sy = (j + 0.5) / h;
                // The pixel's footprint: the widest angle from its centre ray to a corner's.
                double foot = 0.0;
                for (int cy = 0; cy < 2; ++cy)
                    for (int cx = 0; cx < 2; ++cx)
                        foot = std::max(foot, angle_between(dirs[q], rays.at_screen(double(i + cx) / w,
                                                                                   double(j + cy) / h)
                                                                         .direction));
                if (angle_between(dirs[q], s) > alpha + 2.0 * foot) continue;
                const int S = std::clamp(int(std::ceil(8.0 * 2.0 * foot / alpha)), 2, 64);
                std::fill(spectrum.begin(), spectrum.end(), 0.0f);
                bool any = false;
                for (int b = 0; b < S; ++b)
                    for (int a = 0; a < S; ++a) {
                        const CameraRays::Ray ray = rays.at_screen(sx + ((a + 0.5) / S - 0.5) / w,
                                                                   sy + ((b + 0.5) / S - 0.5) / h);
                        const double rho = angle_between(ray.direction, s);
                        if (rho > alpha) continue;
                        const glm::dvec3 rel = ray.origin - centre;
                        const double r = glm::length(rel);
                        if (ray_hits_ground(r, glm::dot(rel, ray.direction) / r, R)) continue;
                        any = true;
                        for (std::size_t c = 0; c < nc; ++c)
                            spectrum[c] += float(mean_radiance[c] * ld[c](rho) / (S * S));
                    }
                if (!any) continue;
                const std::array<double, 3> add = sun_to_rgb.convert(spectrum);
                for (int c = 0; c < 3; ++c) plate.sky[q * 3 + c] += float(add[c] * scene.exposure);
            }
    });
    check(progress, 0.65);

    // Aerial perspective over the band's ground pixels (fitted to the whole frame's depth).
    ProgressStage stage(progress, 0.65, 1.0);
    AerialPasses aerial = aerial_perspective(scene, plate.depth, w, h, &stage, band);
    plate.inscatter = std::move(aerial.inscatter);
    plate.transmittance = std::move(aerial.transmittance);
    check(progress, 1.0);
    // The band's clouds, ending at the whole frame's ground depth (before it is cropped).
    CloudPasses passes;
    if (clouds) {
        ProgressStage cloud_stage(host_progress, 0.3, 1.0);
        passes = render_cloud_passes(scene, *clouds, plate.depth, host_progress ? &cloud_stage : nullptr, band);
    }
    // Keep the band's rows only.
    if (band.begin != 0 || band.end != h) {
        const auto crop = [&](std::vector<float>& v, std::size_t channels) {
            v = std::vector<float>(v.begin() + std::ptrdiff_t(q0 * channels), v.begin() + std::ptrdiff_t(q1 * channels));
        };
        crop(plate.sky, 3);
        crop(plate.inscatter, 3);
        crop(plate.transmittance, 3);
        crop(plate.depth, 1);
    }
    plate.height = band.size();
    plate.row_begin = band.begin;
    plate.frame_height = h;
    const std::size_t nb = q1 - q0;
    plate.combined.resize(nb * 3);
    for (std::size_t k = 0; k < nb * 3; ++k) plate.combined[k] = plate.sky[k] + plate.inscatter[k];

    // Clouds over the sky and the hazed ground (cloud_passes.hpp): the ground (depth) hides
    // what is below it, and Combined = Clouds.rgb + (1 - Clouds.a) (Image x T + Inscatter)
    // with Image x T + Inscatter = the clear plate's combined (Image = the sky with its
    // disc, T = 1 on sky pixels; Image = 0 on the black ground): so the sun's disc is dimmed
    // by the cloud's transmittance, 1 - alpha.
    if (clouds) {
        for (std::size_t q = 0; q < nb; ++q) {
            const float* c = &passes.clouds[q * 4];
            for (int k = 0; k < 3; ++k)
                plate.combined[q * 3 + k] = composite_clouds(c[k], c[3], plate.combined[q * 3 + k], 1.0f, 0.0f);
        }
        plate.clouds = std::move(passes.clouds);
        plate.cloud_depth = std::move(passes.depth);
    } else {
        plate.clouds.assign(nb * 4, 0.0f);
        plate.cloud_depth.assign(nb, kNoCloudDepth);
    }
    if (host_progress && !host_progress->report(1.0)) throw Cancelled();
    return plate;
}

}  // namespace welkin
