// SPDX-License-Identifier: Apache-2.0
// `welkin sun`: the sun at the observer, as JSON: transmittance, direct irradiance per
// wavelength and in RGB (what a Blender sun lamp should carry so that sky and sun agree).
#include <memory>
#include <optional>

#include "common.hpp"
#include "place_and_time.hpp"
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "welkin/atmosphere/sun.hpp"
#include "welkin/base/math.hpp"
#include "welkin/color/color.hpp"

namespace welkin::cli {
namespace {

struct SunArgs {
    AtmosphereArgs atmosphere;
    ObserverArgs observer;
    std::string color_space = "rec709";
    PlaceTimeArgs place_time;
};

int run_sun(SunArgs args) {
    const std::optional<PlaceTime> place_time = resolve_place_time(args.place_time, args.observer);
    const Atmosphere atm = load_atmosphere(args.atmosphere);
    const Observer observer = make_observer(args.observer);
    const SunRadiometry sun = sun_radiometry(atm, observer);
    const double omega = kTwoPi * (1.0 - std::cos(atm.sun_angular_radius_rad));
    nlohmann::ordered_json j = {
        {"atmosphere", args.atmosphere.file.empty() ? atm.name : args.atmosphere.file},
        {"altitude_m", observer.altitude_m},
        {"sun_elevation_deg", args.observer.sun_elevation_deg},
        {"sun_azimuth_deg", args.observer.sun_azimuth_deg},
        {"sun_direction", {observer.sun_direction.x, observer.sun_direction.y, observer.sun_direction.z}},
        {"sun_angular_radius_rad", atm.sun_angular_radius_rad},
        {"sun_solid_angle_sr", omega},
        {"visible_fraction", sun.visible_fraction},
        {"wavelengths_nm", atm.wavelengths_nm},
        {"solar_irradiance_W_m2_nm", atm.solar_irradiance},
        {"transmittance", sun.transmittance},
        {"direct_irradiance_W_m2_nm", sun.direct_irradiance}};
    if (atm.channels() >= 3) {
        // Sunlight converts with lambda power 0 (Bruneton's sun factors) when three
        // wavelengths; spectrally otherwise. Units: W m^-2, CIE-weighted, no 683.
        const SpectrumToRgb to_rgb(atm.wavelengths_nm, 0.0, color_space_from_name(args.color_space));
        j["color_space"] = args.color_space;
        const std::vector<float> e(sun.direct_irradiance.begin(), sun.direct_irradiance.end());
        const std::array<double, 3> rgb = to_rgb.convert(e);
        j["direct_irradiance_rgb_W_m2"] = rgb;
        j["disc_mean_radiance_rgb_W_m2_sr"] = {rgb[0] / omega, rgb[1] / omega, rgb[2] / omega};
    }
    if (place_time) {
        // A moon lamp: the moon's light through the air towards it (a "sun" of the moon's
        // size there), times its brightness relative to the sun's (astro/moonlight.hpp).
        Atmosphere moon_atm = atm;
        moon_atm.sun_angular_radius_rad = place_time->sky.moon.angular_radius_deg * kDegree;
        Observer lit = observer;
        const auto& m = place_time->sky.moon.direction_enu;
        lit.sun_direction = {m[0], m[1], m[2]};
        const SunRadiometry moon = sun_radiometry(moon_atm, lit.validated());
        std::vector<double> e(moon.direct_irradiance);
        for (double& v : e) v *= place_time->sky.moon_irradiance_ratio;
        j["moon_direct_irradiance_W_m2_nm"] = e;
        if (atm.channels() >= 3) {
            const std::vector<float> ef(e.begin(), e.end());
            j["moon_direct_irradiance_rgb_W_m2"] = SpectrumToRgb(atm.wavelengths_nm, 0.0).convert(ef);
        }
        j["place_and_time"] = place_time->json();
    }
    fmt::print("{}\n", j.dump(2));
    return 0;
}

}  // namespace

Command add_sun_command(CLI::App& app) {
    auto args = std::make_shared<SunArgs>();
    CLI::App* sub = app.add_subcommand(
        "sun", "Print the sun's transmittance and direct irradiance at the observer (JSON)");
    add_atmosphere_options(sub, args->atmosphere);
    add_observer_options(sub, args->observer);
    add_color_space_option(sub, args->color_space);
    add_place_time_options(sub, args->place_time);
    sub->footer(
        "direct_irradiance is the normal-incidence irradiance of the sun's disc at the "
        "observer, E_sun * T * visible fraction (W m^-2 nm^-1 per wavelength; linear "
        "RGB of --color-space, Rec.709 by default, W m^-2 for the RGB triple): the strength of a "
        "matching Blender sun lamp. "
        "With --time, --latitude and --longitude the sun is placed from the place and the moment, and "
        "place_and_time holds the apparent sun and moon (elevation, "
        "azimuth clockwise from north) and the moon's illuminated fraction; "
        "moon_direct_irradiance is then the moon's, the strength of a moon lamp.");
    return {sub, [args] { return run_sun(*args); }};
}

}  // namespace welkin::cli
