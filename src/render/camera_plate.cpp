// SPDX-License-Identifier: Apache-2.0
// The camera plate: sky, sun disc and aerial perspective over the ground; see
// camera_plate.hpp.
#include "welkin/render/camera_plate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "welkin/aerial/aerial_perspective.hpp"
#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/ground.hpp"
#include "welkin/atmosphere/sun_disc.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"
#include "welkin/base/memory.hpp"
#include "welkin/color/color.hpp"
#include "welkin/render/cloud_passes.hpp"
#include "welkin/sky/auto.hpp"
#include "welkin/sky/method.hpp"

namespace welkin {
namespace {

void check(Progress* p, double f) {
    if (p && !p->report(f)) throw Cancelled();
}

double angle_between(const glm::dvec3& a, const glm::dvec3& b) {
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

}  // namespace

// The frame-wide part (camera_plate.hpp, "Rows"), once.
struct CameraPlateRenderer::Impl {
    explicit Impl(const SceneDescription& s)
        : scene(checked(s)),
          w(scene.resolution.width()),
          h(scene.resolution.height()),
          rays(scene.require_camera(), w, h),
          // The clouds' density before any work: a bad VDB is refused first.
          clouds(scene.cloud_density()),
          centre(scene.planet_centre()),
          R(scene.atmosphere.bottom_radius_m) {
        const Atmosphere& atm = scene.atmosphere;
        const double cam_r = glm::length(rays.position() - centre);
        if (!(cam_r >= R))
            throw InvalidArgument("camera.matrix_world",
                                  fmt::format("puts the camera {:.6g} m below the ground (it must stand "
                                              "at or above altitude 0 m)",
                                              R - cam_r));
        observer = Observer{cam_r - R, scene.sun_direction}.validated();

        // Depth to the ground sphere per pixel (Z-pass units), +infinity for sky pixels.
        const std::size_t n = std::size_t(w) * std::size_t(h);
        depth.assign(n, std::numeric_limits<float>::infinity());
        tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const auto& rows) {
            for (int j = rows.begin(); j != rows.end(); ++j)
                for (int i = 0; i < w; ++i) {
                    const CameraRays::Ray ray = rays.at_pixel(i, j);
                    const std::size_t q = std::size_t(j) * std::size_t(w) + std::size_t(i);
                    const glm::dvec3 rel = ray.origin - centre;
                    const double r = glm::length(rel);
                    const double mu = glm::dot(rel, ray.direction) / r;
                    if (r > R && ray_hits_ground(r, mu, R))
                        depth[q] = float(distance_to_bottom(r, mu, R) / ray.distance_per_depth);
                    else if (r <= R)
                        depth[q] = 0.0f;  // an orthographic ray starting underground
                }
        });
        // "auto" chooses by the number of directions: choose here for the whole frame's sky
        // pixels, so that a band renders with the method the whole frame would (AutoSky makes
        // the same choice for a whole-frame call).
        if (scene.method == "auto") {
            std::size_t frame_sky = 0;
            for (const float z : depth) frame_sky += std::isinf(z) ? 1 : 0;
            const AutoChoice c = choose_sky_method(atm, observer, std::max<std::size_t>(frame_sky, 1),
                                                   scene.sky_options.tolerance, scene.sky_options);
            method = make_sky_method(c.method, c.options);
        } else {
            method = make_sky_method(scene.method, scene.sky_options);
        }
        method_name = method->name();

        // The sun's disc (sun_disc.hpp), on the samples of the disc above the horizon.
        sun = std::make_unique<SunDisc>(atm, observer);

        // The lit ground (ground.hpp): its irradiance tables, when the frame sees it.
        bool sees_ground = false;
        for (const float z : depth) sees_ground = sees_ground || (std::isfinite(z) && z > 0.0f);
        if (scene.ground && sees_ground) {
            ground = GroundIllumination::shared(atm);
            for (std::size_t c = 0; c < atm.channels(); ++c)
                ground_albedo_over_pi.push_back(
                    (scene.ground_albedo ? *scene.ground_albedo : atm.ground_albedo[c]) / kPi);
        }

        // The aerial perspective, fitted to the whole frame's depth.
        aerial = std::make_unique<AerialFrame>(scene.aerial_view(), depth, w, h);

        // The clouds' light and shadow grids, shared by the bands.
        if (clouds) cloud_passes = std::make_unique<CloudPassRenderer>(scene, *clouds);
    }

    // The scene validated, with a camera, and a resolution that fits in memory.
    static const SceneDescription& checked(const SceneDescription& s) {
        s.validate();
        s.require_camera();
        check_frame_memory(s.resolution.width(), s.resolution.height(),
                           kAerialPassBytesPerPixel + 18 * sizeof(float), "plate and its passes (float)");
        return s;
    }

    // The steps of render() over a band's rows (plate.depth already cut to the band).
    void add_sky(CameraPlate& plate, const std::vector<std::size_t>& sky_pixels,
                 const std::vector<glm::dvec3>& sky_dirs, const SpectrumToRgb& sky_to_rgb,
                 Progress* progress) const;
    void add_sun_disc(CameraPlate& plate, RowRange band, const SpectrumToRgb& sun_to_rgb) const;
    void add_lit_ground(CameraPlate& plate, RowRange band, const SpectrumToRgb& sun_to_rgb) const;
    void add_clouds(CameraPlate& plate, RowRange band, Progress* host_progress) const;

    SceneDescription scene;
    int w, h;
    CameraRays rays;
    std::shared_ptr<const CloudDensity> clouds;
    glm::dvec3 centre;
    double R;
    Observer observer;
    std::vector<float> depth;  // (h, w), the whole frame's
    std::unique_ptr<SkyMethod> method;
    std::string method_name;
    std::unique_ptr<SunDisc> sun;
    std::shared_ptr<const GroundIllumination> ground;  // null: no ground in view, or switched off
    std::vector<double> ground_albedo_over_pi;
    std::unique_ptr<AerialFrame> aerial;
    std::unique_ptr<CloudPassRenderer> cloud_passes;  // null without clouds
};

CameraPlateRenderer::CameraPlateRenderer(const SceneDescription& scene)
    : impl_(std::make_unique<Impl>(scene)) {}
CameraPlateRenderer::~CameraPlateRenderer() = default;
int CameraPlateRenderer::width() const { return impl_->w; }
int CameraPlateRenderer::height() const { return impl_->h; }
const std::string& CameraPlateRenderer::method() const { return impl_->method_name; }
bool CameraPlateRenderer::has_clouds() const { return bool(impl_->clouds); }

// The sky's radiance on the band's sky pixels (q relative to the band), one call.
void CameraPlateRenderer::Impl::add_sky(CameraPlate& plate, const std::vector<std::size_t>& sky_pixels,
                                        const std::vector<glm::dvec3>& sky_dirs,
                                        const SpectrumToRgb& sky_to_rgb, Progress* progress) const {
    const Atmosphere& atm = scene.atmosphere;
    ProgressStage stage(progress, 0.02, 0.6);
    const SkyResult sky = sky_radiance(*method, atm, observer, sky_dirs, &stage);
    std::vector<float> rgb(sky_dirs.size() * 3);
    sky_to_rgb.convert(sky.radiance, rgb);
    for (std::size_t k = 0; k < sky_pixels.size(); ++k)
        for (int c = 0; c < 3; ++c) {
            const float v = rgb[k * 3 + c];
            if (!std::isfinite(v))
                throw std::runtime_error(
                    fmt::format("sky method {} returned a non-finite radiance", plate.method));
            plate.sky[sky_pixels[k] * 3 + c] = v * float(scene.exposure);
        }
}

// The sun's disc on the band's sky pixels (Impl: its mean radiance and limb darkening).
void CameraPlateRenderer::Impl::add_sun_disc(CameraPlate& plate, RowRange band,
                                             const SpectrumToRgb& sun_to_rgb) const {
    const Atmosphere& atm = scene.atmosphere;
    const std::size_t nc = atm.channels();
    const SunDisc& disc = *sun;
    const double alpha = disc.angular_radius_rad();
    const glm::dvec3 s = disc.direction();
    tbb::parallel_for(tbb::blocked_range<int>(band.begin, band.end), [&](const auto& rows) {
        std::vector<double> spectrum_d(nc);
        std::vector<float> spectrum(nc);
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const std::size_t q = std::size_t(j - band.begin) * std::size_t(w) + std::size_t(i);
                if (!std::isinf(plate.depth[q]) || disc.radiometry().visible_fraction <= 0.0) continue;
                const glm::dvec3 dir = rays.at_pixel(i, j).direction;
                const double sx = (i + 0.5) / w, sy = (j + 0.5) / h;
                // The pixel's footprint: the widest angle from its centre ray to a corner's.
                double foot = 0.0;
                for (int cy = 0; cy < 2; ++cy)
                    for (int cx = 0; cx < 2; ++cx)
                        foot = std::max(
                            foot, angle_between(
                                      dir, rays.at_screen(double(i + cx) / w, double(j + cy) / h).direction));
                if (angle_between(dir, s) > alpha + 2.0 * foot) continue;
                const int S = std::clamp(int(std::ceil(8.0 * 2.0 * foot / alpha)), 2, 64);
                std::fill(spectrum_d.begin(), spectrum_d.end(), 0.0);
                bool any = false;
                for (int b = 0; b < S; ++b)
                    for (int a = 0; a < S; ++a) {
                        const CameraRays::Ray ray =
                            rays.at_screen(sx + ((a + 0.5) / S - 0.5) / w, sy + ((b + 0.5) / S - 0.5) / h);
                        const double rho = angle_between(ray.direction, s);
                        if (rho > alpha) continue;
                        const glm::dvec3 rel = ray.origin - centre;
                        const double r = glm::length(rel);
                        if (ray_hits_ground(r, glm::dot(rel, ray.direction) / r, R)) continue;
                        any = disc.add_radiance(rho, 1.0 / (S * S), spectrum_d) || any;
                    }
                if (!any) continue;
                for (std::size_t c = 0; c < nc; ++c) spectrum[c] = float(spectrum_d[c]);
                const std::array<double, 3> add = sun_to_rgb.convert(spectrum);
                for (int c = 0; c < 3; ++c) plate.sky[q * 3 + c] += float(add[c] * scene.exposure);
            }
    });
}

// The lit ground seen through the air (camera_plate.hpp): + T x albedo / pi x E(p).
void CameraPlateRenderer::Impl::add_lit_ground(CameraPlate& plate, RowRange band,
                                               const SpectrumToRgb& sun_to_rgb) const {
    const std::size_t nc = scene.atmosphere.channels();
    const glm::dvec3 s = sun->direction();
    tbb::parallel_for(tbb::blocked_range<int>(band.begin, band.end), [&](const auto& rows) {
        std::vector<double> e(nc);
        std::vector<float> surface(nc);
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const std::size_t q = std::size_t(j - band.begin) * std::size_t(w) + std::size_t(i);
                const float z = plate.depth[q];
                if (!std::isfinite(z) || !(z > 0.0f)) continue;
                const CameraRays::Ray ray = rays.at_pixel(i, j);
                const glm::dvec3 p = ray.origin + double(z) * ray.distance_per_depth * ray.direction - centre;
                ground->irradiance(glm::dot(glm::normalize(p), s), e);
                for (std::size_t c = 0; c < nc; ++c) surface[c] = float(ground_albedo_over_pi[c] * e[c]);
                const std::array<double, 3> rgb = sun_to_rgb.convert(surface);
                for (int k = 0; k < 3; ++k)
                    plate.combined[q * 3 + k] +=
                        plate.transmittance[q * 3 + k] * float(rgb[k] * scene.exposure);
            }
    });
}

// Clouds over the sky and the hazed ground (cloud_passes.hpp): the band's clouds, ending
// at the whole frame's ground depth, so the ground (depth) hides what is below it, and
// Combined = Clouds.rgb + (1 - Clouds.a) (Image x T + Inscatter) with Image x T +
// Inscatter = the clear plate's combined (Image = the sky with its disc, T = 1 on sky
// pixels; Image = 0 on the black ground): so the sun's disc is dimmed by the cloud's
// transmittance, 1 - alpha.
void CameraPlateRenderer::Impl::add_clouds(CameraPlate& plate, RowRange band, Progress* host_progress) const {
    const std::size_t nb = std::size_t(band.size()) * std::size_t(w);
    if (clouds) {
        ProgressStage cloud_stage(host_progress, 0.3, 1.0);
        CloudPasses passes = cloud_passes->render(depth, host_progress ? &cloud_stage : nullptr, band);
        for (std::size_t q = 0; q < nb; ++q) {
            const float* c = &passes.clouds[q * 4];
            for (int k = 0; k < 3; ++k)
                plate.combined[q * 3 + k] =
                    composite_clouds(c[k], c[3], plate.combined[q * 3 + k], 1.0f, 0.0f);
        }
        plate.clouds = std::move(passes.clouds);
        plate.cloud_depth = std::move(passes.depth);
    } else {
        plate.clouds.assign(nb * 4, 0.0f);
        plate.cloud_depth.assign(nb, kNoCloudDepth);
    }
}

CameraPlate CameraPlateRenderer::render(RowRange rows_in, Progress* host_progress) const {
    const Impl& f = *impl_;
    const SceneDescription& scene = f.scene;
    const Atmosphere& atm = scene.atmosphere;
    const int w = f.w, h = f.h;
    const RowRange band = rows_in.resolved(h);
    const std::size_t q0 = std::size_t(band.begin) * std::size_t(w);
    const std::size_t nb = std::size_t(band.size()) * std::size_t(w);
    // The clouds' march takes most of the time: the sky and the air get the first 30 % of
    // the progress.
    ProgressStage clear_stage(host_progress, 0.0, f.clouds ? 0.3 : 1.0);
    Progress* progress = host_progress ? &clear_stage : nullptr;
    check(progress, 0.0);

    CameraPlate plate;
    plate.width = w;
    plate.height = band.size();
    plate.row_begin = band.begin;
    plate.frame_height = h;
    plate.method = f.method_name;
    plate.depth.assign(f.depth.begin() + std::ptrdiff_t(q0), f.depth.begin() + std::ptrdiff_t(q0 + nb));

    // The band's sky pixels (q relative to the band) and their view directions.
    std::vector<std::size_t> sky_pixels;
    std::vector<glm::dvec3> sky_dirs;
    for (std::size_t q = 0; q < nb; ++q)
        if (std::isinf(plate.depth[q])) {
            sky_pixels.push_back(q);
            sky_dirs.push_back(
                f.rays.at_pixel(int((q0 + q) % std::size_t(w)), int((q0 + q) / std::size_t(w))).direction);
        }
    const SpectrumToRgb sky_to_rgb(atm.wavelengths_nm, -3.0, scene.color_space),
        sun_to_rgb(atm.wavelengths_nm, 0.0, scene.color_space);
    plate.sky.assign(nb * 3, 0.0f);
    if (!sky_dirs.empty()) f.add_sky(plate, sky_pixels, sky_dirs, sky_to_rgb, progress);
    check(progress, 0.6);

    f.add_sun_disc(plate, band, sun_to_rgb);
    check(progress, 0.65);

    // Aerial perspective over the band's ground pixels (fitted to the whole frame's depth).
    {
        ProgressStage stage(progress, 0.65, 1.0);
        plate.inscatter.resize(nb * 3);
        plate.transmittance.resize(nb * 3);
        f.aerial->render(band, plate.inscatter, plate.transmittance, &stage);
    }
    check(progress, 1.0);
    plate.combined.resize(nb * 3);
    for (std::size_t k = 0; k < nb * 3; ++k) plate.combined[k] = plate.sky[k] + plate.inscatter[k];
    if (f.ground) f.add_lit_ground(plate, band, sun_to_rgb);

    f.add_clouds(plate, band, host_progress);
    if (host_progress && !host_progress->report(1.0)) throw Cancelled();
    return plate;
}

CameraPlate render_camera_plate(const SceneDescription& scene, Progress* progress, RowRange rows) {
    if (progress && !progress->report(0.0)) throw Cancelled();
    return CameraPlateRenderer(scene).render(rows, progress);
}

}  // namespace welkin
