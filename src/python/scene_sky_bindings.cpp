// SPDX-License-Identifier: Apache-2.0
// welkin.scene_sky_image: the equirectangular sky of a scene description, its clouds
// included, as `welkin sky --scene` renders it (sky_image.hpp): the scene's atmosphere, sun,
// observer at the scene origin, sky method and options, exposure, and its clouds (layers and
// VDB volumes, lit with clouds.lighting). Thin: converts, releases the GIL, calls the core.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "bindings.hpp"
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "welkin/base/error.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/night/moonlit_sky.hpp"
#include "welkin/night/night_glow.hpp"
#include "welkin/night/stars.hpp"
#include "welkin/render/sky_image.hpp"
#include "welkin/scene/scene.hpp"

namespace welkin::python {

namespace {

constexpr const char* kSceneSkyDoc = R"doc(
The equirectangular sky of a scene, with its clouds (the world texture of a cloudy sky).

    img = welkin.scene_sky_image(scene, width, sun_disc=True, output="rgb")
    img, T = welkin.scene_sky_image(scene, width, return_transmittance=True)

scene: a welkin.SceneDescription or its JSON text. The observer stands at the scene
origin (origin_altitude_m); the sky method, its options and the exposure are the scene's;
its "clouds" (if any) are composited over the sky as in sky_image(clouds=...), lit with
clouds.lighting and clouds.scattering. Layout and units as sky_image: (width / 2, width,
3) top row first, linear Rec.709 W m^-2 sr^-1 (output="rgb") or per wavelength
("spectral"), times the exposure. return_transmittance: also the clouds' transmittance
per pixel, (width / 2, width) (ones without clouds), the factor sky_image dims the sun's
disc by (for a disc kept in an image of its own). ValueError names the parameter or the
scene's key (clouds.volumes[i].file for a bad VDB). Cancellable (progress, Ctrl-C).
ground: the lit ground below the horizon with the atmosphere's ground_albedo, as
in sky_image (False: black there).

The night sky of a place and a moment, in the scene's frame (the add-on's Place and
Time; `welkin sky --scene --time` and sky_image_at compose the same): moon_direction,
sun_from_moon, moon_angular_radius_rad and moon_irradiance_ratio as in
moon_disc_image add the moon's light: its sky, and the clouds lit by it as by a "sun"
in its direction times the ratio (left out while the scene's sun is up), and with
sun_disc its disc with its phase, dimmed by the clouds' transmittance. stars: an (N, 5)
array as stars_at returns (directions in the scene's frame), drawn energy-exact and
dimmed by the air and by the clouds' transmittance; night_glow=True adds the night
sky's own glow (welkin.night_glow_image), dimmed the same way. time, latitude_deg,
longitude_deg, height_m, north_deg: the moment and place that put the ecliptic (and
so the zodiacal light) in the scene's frame, as night_glow_image's; time=None: the
zodiacal light at its darkest everywhere. keep_cloud_samples: the clouds' view samples
(where each marched ray meets cloud) are kept for the next call, and a call whose scene
differs only in its sun (and the light: its time, moon, stars) lights them again instead
of marching the clouds: the same image, bit for bit, in a fraction of the time (a lamp
rotation, an animated sun). The last two cloudy skies' are kept (each at most 128 MB: a
preview and its full sky); False: none read or kept.
)doc";

// The moon of the keyword arguments, or none (no moon_direction).
std::optional<Moon> moon_from(const py::object& direction, const py::object& sun_from_moon,
                              double angular_radius_rad, double irradiance_ratio, bool disc) {
    if (direction.is_none()) return std::nullopt;
    Moon moon;
    moon.direction = to_dvec3(direction, "moon_direction");
    if (sun_from_moon.is_none()) throw InvalidArgument("sun_from_moon", "is required with moon_direction");
    moon.sun_from_moon = to_dvec3(sun_from_moon, "sun_from_moon");
    for (const auto& [v, name] :
         {std::pair{moon.direction, "moon_direction"}, std::pair{moon.sun_from_moon, "sun_from_moon"}})
        if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) ||
            (v.x == 0.0 && v.y == 0.0 && v.z == 0.0))
            throw InvalidArgument(name, "must be a finite non-zero vector");
    moon.angular_radius_rad = angular_radius_rad;
    moon.irradiance_ratio = irradiance_ratio;
    moon.disc = disc;
    moon.validate();  // the radius and the ratio, named moon.<field> (as moon_disc_image)
    return moon;
}

// The clouds' view samples of the last cloudy skies (clouds/lighting.hpp, CloudViewCache),
// one per scene key: the add-on's live update renders a preview and then the full sky after
// each lamp rotation, and a render of an animated sun the next frame's; each lights its own
// kept samples instead of marching the clouds again. Two slots (the preview and the sky),
// each at most kSlotBytes; a call takes its key's slot, else the one used least recently
// (emptied for it), else (both in use by other calls) runs without one.
class ViewCacheSlots {
public:
    static constexpr std::size_t kSlotBytes = std::size_t(128) << 20;

    // The slot's cache while the guard lives; null: none free.
    class Taken {
    public:
        Taken() = default;
        Taken(ViewCacheSlots* owner, std::size_t slot) : owner_(owner), slot_(slot) {}
        Taken(Taken&& o) noexcept : owner_(std::exchange(o.owner_, nullptr)), slot_(o.slot_) {}
        Taken& operator=(Taken&& o) noexcept {
            if (this != &o) {
                release();
                owner_ = std::exchange(o.owner_, nullptr);
                slot_ = o.slot_;
            }
            return *this;
        }
        ~Taken() { release(); }
        std::shared_ptr<CloudViewCache> cache() const {
            return owner_ ? owner_->slots_[slot_].cache : nullptr;
        }

    private:
        void release() {
            if (!owner_) return;
            std::lock_guard<std::mutex> lock(owner_->mutex_);
            owner_->slots_[slot_].busy = false;
            owner_ = nullptr;
        }
        ViewCacheSlots* owner_ = nullptr;
        std::size_t slot_ = 0;
    };

    Taken take(const std::string& key) {
        std::lock_guard<std::mutex> lock(mutex_);
        std::size_t pick = slots_.size();
        for (std::size_t k = 0; k < slots_.size(); ++k)
            if (!slots_[k].busy && slots_[k].key == key) pick = k;
        if (pick == slots_.size())
            for (std::size_t k = 0; k < slots_.size(); ++k)
                if (!slots_[k].busy && (pick == slots_.size() || slots_[k].used < slots_[pick].used))
                    pick = k;
        if (pick == slots_.size()) return {};
        Slot& s = slots_[pick];
        if (!s.cache) s.cache = std::make_shared<CloudViewCache>(kSlotBytes);
        s.cache->keep(key);
        s.key = key;
        s.busy = true;
        s.used = ++clock_;
        return {this, pick};
    }

    static ViewCacheSlots& instance() {
        static auto* slots = new ViewCacheSlots;  // never destroyed: a call may outlive the statics
        return *slots;
    }

private:
    struct Slot {
        std::string key;
        std::shared_ptr<CloudViewCache> cache;
        std::uint64_t used = 0;
        bool busy = false;
    };
    std::mutex mutex_;
    std::array<Slot, 2> slots_;
    std::uint64_t clock_ = 0;
};

py::object scene_sky_image(const py::handle& scene_in, int width, bool sun_disc, const std::string& output,
                           bool return_transmittance, const py::object& progress, bool ground,
                           const py::object& moon_direction, const py::object& sun_from_moon,
                           double moon_angular_radius_rad, double moon_irradiance_ratio,
                           const std::optional<py::array_t<double>>& stars, bool night_glow,
                           const py::object& time, double latitude_deg, double longitude_deg, double height_m,
                           double north_deg, bool keep_cloud_samples) {
    SceneDescription scene = to_scene(scene_in);
    require_progress_callback(progress);
    const std::optional<Moon> moon =
        moon_from(moon_direction, sun_from_moon, moon_angular_radius_rad, moon_irradiance_ratio, sun_disc);
    const std::vector<Star> star_list = stars ? to_stars(*stars) : std::vector<Star>{};
    const NightGlowOptions glow = night_glow_options(time, latitude_deg, longitude_deg, height_m, north_deg);
    SkyImageOptions options;
    options.sun_disc = sun_disc;
    options.ground = ground && scene.ground;
    options.ground_albedo = scene.ground_albedo;
    options.exposure = scene.exposure;
    options.color_space = scene.color_space;
    options.output = parse_output(output);
    SkyImage image;
    run_cancellable(
        [&](Progress* p) {
            ViewCacheSlots::Taken kept;
            if (scene.has_clouds()) {
                options.clouds = scene.cloud_density();  // opens the VDB files
                options.cloud_lighting = scene.clouds->lighting;
                if (keep_cloud_samples) {
                    kept =
                        ViewCacheSlots::instance().take(fmt::format("{}|{}", width, scene.cloud_view_key()));
                    options.cloud_lighting.view_cache = kept.cache();
                }
                options.cloud_upsampling = scene.clouds->upsampling;
                options.air_steps = scene.aerial.raymarch_steps;
            }
            const std::unique_ptr<SkyMethod> method = make_sky_method(scene.method, scene.sky_options);
            const Observer observer = scene.origin_observer();
            image = moon ? render_equirect_sky_with_moon(*method, scene.atmosphere, observer, *moon, width,
                                                         options, p)
                         : render_equirect_sky(*method, scene.atmosphere, observer, width, options, p);
            if (night_glow) add_night_glow(image, scene.atmosphere, observer, options, glow);
            add_stars(image, scene.atmosphere, observer, star_list, options);
        },
        progress);
    const int w = image.width, h = image.height;
    std::vector<float> transmittance = std::move(image.cloud_transmittance);
    const std::size_t channels = image.channels();
    py::array_t<float> pixels = to_image_array(std::move(image.pixels), w, h, channels);
    if (!return_transmittance) return pixels;
    if (transmittance.empty()) transmittance.assign(std::size_t(w) * std::size_t(h), 1.0f);
    py::array_t<float> t({py::ssize_t(h), py::ssize_t(w)});
    std::copy(transmittance.begin(), transmittance.end(), t.mutable_data());
    return py::make_tuple(pixels, t);
}

}  // namespace

void register_scene_sky(py::module_& m) {
    m.def(
        "scene_sky_image", &scene_sky_image, kSceneSkyDoc, py::arg("scene"), py::arg("width"), py::kw_only(),
        py::arg("sun_disc") = true, py::arg("output") = "rgb", py::arg("return_transmittance") = false,
        py::arg("progress") = py::none(), py::arg("ground") = true, py::arg("moon_direction") = py::none(),
        py::arg("sun_from_moon") = py::none(), py::arg("moon_angular_radius_rad") = Moon{}.angular_radius_rad,
        py::arg("moon_irradiance_ratio") = 0.0, py::arg("stars") = py::none(), py::arg("night_glow") = false,
        py::arg("time") = py::none(), py::arg("latitude_deg") = 0.0, py::arg("longitude_deg") = 0.0,
        py::arg("height_m") = 0.0, py::arg("north_deg") = 0.0, py::arg("keep_cloud_samples") = true);
}

}  // namespace welkin::python
