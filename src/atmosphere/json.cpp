// SPDX-License-Identifier: Apache-2.0
// JSON form of an Atmosphere.
//
// Schema (every key optional when "preset" is given; the preset fills what is missing):
//   {
//     "preset": "bruneton2017",            // base to start from
//     "name": "my sky",
//     "wavelengths_nm": [680, 550, 440],   // with "preset": resamples its spectral models
//     "solar_irradiance": [..] | number,   // W m^-2 nm^-1, one per wavelength or one for all
//     "sun_angular_radius_rad": 0.004675,
//     "bottom_radius_m": 6360000, "top_radius_m": 6420000,
//     "rayleigh":   {"scattering": [..] | number, "density": PROFILE},
//     "mie":        {"scattering": .., "extinction": .., "phase": "cornette_shanks" |
//                    "henyey_greenstein", "g": 0.8, "density": PROFILE},
//     "absorption": {"extinction": .., "density": PROFILE},
//     "ground_albedo": [..] | number
//   }
// PROFILE is {"exponential_scale_height_m": H}, {"tent_m": [bottom, peak, top]}, "zero", or
// {"layers": [{"width_m", "exp_term", "exp_scale_per_m", "linear_per_m", "constant"}, ..]}.
// to_json writes the explicit form (layers and arrays), so a file reproduces the
// atmosphere exactly.
#include "welkin/io/json.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"

namespace welkin {
namespace {

using nlohmann::json;

std::vector<double> spectrum(const json& j, const std::string& parameter, std::size_t channels) {
    if (j.is_number()) return std::vector<double>(channels, j.get<double>());
    if (!j.is_array())
        throw InvalidArgument(parameter, fmt::format("must be a number or an array of {} numbers", channels));
    std::vector<double> v;
    for (std::size_t i = 0; i < j.size(); ++i)
        v.push_back(json_number(j[i], fmt::format("{}[{}]", parameter, i)));
    return v;
}

DensityProfile profile(const json& j, const std::string& parameter) {
    if (j.is_string() && j.get<std::string>() == "zero") return DensityProfile::zero();
    if (!j.is_object())
        throw InvalidArgument(parameter,
                              "must be an object with 'exponential_scale_height_m', "
                              "'tent_m' or 'layers', or the string \"zero\"");
    if (j.contains("exponential_scale_height_m"))
        return DensityProfile::exponential(
            json_number(j["exponential_scale_height_m"], parameter + ".exponential_scale_height_m"));
    if (j.contains("tent_m")) {
        const json& t = j["tent_m"];
        if (!t.is_array() || t.size() != 3)
            throw InvalidArgument(parameter + ".tent_m", "must be [bottom, peak, top] in metres");
        return DensityProfile::tent(json_number(t[0], parameter + ".tent_m[0]"),
                                    json_number(t[1], parameter + ".tent_m[1]"),
                                    json_number(t[2], parameter + ".tent_m[2]"));
    }
    if (j.contains("layers") && j["layers"].is_array()) {
        std::vector<DensityLayer> layers;
        for (std::size_t i = 0; i < j["layers"].size(); ++i) {
            const json& l = j["layers"][i];
            const std::string p = fmt::format("{}.layers[{}]", parameter, i);
            if (!l.is_object()) throw InvalidArgument(p, "must be an object");
            auto get = [&](const char* key) {
                return l.contains(key) ? json_number(l[key], p + "." + key) : 0.0;
            };
            layers.push_back({get("width_m"), get("exp_term"), get("exp_scale_per_m"), get("linear_per_m"),
                              get("constant")});
        }
        return DensityProfile(std::move(layers));
    }
    throw InvalidArgument(parameter, "needs 'exponential_scale_height_m', 'tent_m' or 'layers'");
}

json profile_json(const DensityProfile& p) {
    json layers = json::array();
    for (const DensityLayer& l : p.layers())
        layers.push_back({{"width_m", l.width_m},
                          {"exp_term", l.exp_term},
                          {"exp_scale_per_m", l.exp_scale_per_m},
                          {"linear_per_m", l.linear_per_m},
                          {"constant", l.constant}});
    return {{"layers", layers}};
}

Atmosphere parse(const json& j) {
    if (!j.is_object()) throw InvalidArgument("atmosphere", "JSON must be an object");
    json_check_keys(
        j, "",
        {"preset", "name", "wavelengths_nm", "solar_irradiance", "sun_angular_radius_rad", "bottom_radius_m",
         "top_radius_m", "rayleigh", "mie", "absorption", "ground_albedo", "$schema", "comment"});
    std::vector<double> wavelengths;
    if (j.contains("wavelengths_nm")) wavelengths = spectrum(j["wavelengths_nm"], "wavelengths_nm", 0);
    Atmosphere a;
    if (j.contains("preset")) {
        if (!j["preset"].is_string()) throw InvalidArgument("preset", "must be a string");
        a = Atmosphere::preset(j["preset"].get<std::string>(), wavelengths);
    } else {
        a.wavelengths_nm = wavelengths.empty() ? default_wavelengths_nm() : wavelengths;
        a.rayleigh_density = a.mie_density = a.absorption_density = DensityProfile::zero();
    }
    const std::size_t n = a.wavelengths_nm.size();
    if (j.contains("name")) {
        if (!j["name"].is_string()) throw InvalidArgument("name", "must be a string");
        a.name = j["name"].get<std::string>();
    }
    if (j.contains("solar_irradiance"))
        a.solar_irradiance = spectrum(j["solar_irradiance"], "solar_irradiance", n);
    if (j.contains("sun_angular_radius_rad"))
        a.sun_angular_radius_rad = json_number(j["sun_angular_radius_rad"], "sun_angular_radius_rad");
    if (j.contains("bottom_radius_m"))
        a.bottom_radius_m = json_number(j["bottom_radius_m"], "bottom_radius_m");
    if (j.contains("top_radius_m")) a.top_radius_m = json_number(j["top_radius_m"], "top_radius_m");
    if (j.contains("rayleigh")) {
        const json& r = j["rayleigh"];
        if (!r.is_object()) throw InvalidArgument("rayleigh", "must be an object");
        json_check_keys(r, "rayleigh", {"scattering", "density"});
        if (r.contains("scattering"))
            a.rayleigh_scattering = spectrum(r["scattering"], "rayleigh.scattering", n);
        if (r.contains("density")) a.rayleigh_density = profile(r["density"], "rayleigh.density");
    }
    if (j.contains("mie")) {
        const json& m = j["mie"];
        if (!m.is_object()) throw InvalidArgument("mie", "must be an object");
        json_check_keys(m, "mie", {"scattering", "extinction", "phase", "g", "density"});
        if (m.contains("scattering")) a.mie_scattering = spectrum(m["scattering"], "mie.scattering", n);
        if (m.contains("extinction")) a.mie_extinction = spectrum(m["extinction"], "mie.extinction", n);
        if (m.contains("g")) a.mie_g = json_number(m["g"], "mie.g");
        if (m.contains("phase")) {
            const std::string ph = m["phase"].is_string() ? m["phase"].get<std::string>() : "";
            if (ph == "cornette_shanks")
                a.mie_phase = MiePhaseModel::CornetteShanks;
            else if (ph == "henyey_greenstein")
                a.mie_phase = MiePhaseModel::HenyeyGreenstein;
            else
                throw InvalidArgument("mie.phase", fmt::format("must be \"cornette_shanks\" or "
                                                               "\"henyey_greenstein\", got {}",
                                                               m["phase"].dump()));
        }
        if (m.contains("density")) a.mie_density = profile(m["density"], "mie.density");
    }
    if (j.contains("absorption")) {
        const json& o = j["absorption"];
        if (!o.is_object()) throw InvalidArgument("absorption", "must be an object");
        json_check_keys(o, "absorption", {"extinction", "density"});
        if (o.contains("extinction"))
            a.absorption_extinction = spectrum(o["extinction"], "absorption.extinction", n);
        if (o.contains("density")) a.absorption_density = profile(o["density"], "absorption.density");
    }
    if (j.contains("ground_albedo")) a.ground_albedo = spectrum(j["ground_albedo"], "ground_albedo", n);
    // A spectrum omitted without a preset means "none of it".
    for (auto* v : {&a.rayleigh_scattering, &a.mie_scattering, &a.mie_extinction, &a.absorption_extinction,
                    &a.ground_albedo})
        if (v->empty()) v->assign(n, 0.0);
    if (a.solar_irradiance.empty())
        throw InvalidArgument("solar_irradiance", "is required when no preset is given");
    a.validate();
    return a;
}

}  // namespace

Atmosphere Atmosphere::from_json_string(const std::string& text) {
    return parse(parse_json(text, "atmosphere JSON"));
}

Atmosphere Atmosphere::from_json_file(const std::string& path) {
    const json j = read_json_file(path, "atmosphere");
    return with_json_source(path, [&] { return parse(j); });
}

std::string Atmosphere::to_json_string() const {
    validate();
    const char* phase = mie_phase == MiePhaseModel::CornetteShanks ? "cornette_shanks" : "henyey_greenstein";
    json j = {
        {"name", name},
        {"wavelengths_nm", wavelengths_nm},
        {"solar_irradiance", solar_irradiance},
        {"sun_angular_radius_rad", sun_angular_radius_rad},
        {"bottom_radius_m", bottom_radius_m},
        {"top_radius_m", top_radius_m},
        {"rayleigh", {{"scattering", rayleigh_scattering}, {"density", profile_json(rayleigh_density)}}},
        {"mie",
         {{"scattering", mie_scattering},
          {"extinction", mie_extinction},
          {"phase", phase},
          {"g", mie_g},
          {"density", profile_json(mie_density)}}},
        {"absorption",
         {{"extinction", absorption_extinction}, {"density", profile_json(absorption_density)}}},
        {"ground_albedo", ground_albedo}};
    return j.dump(2);
}

void Atmosphere::to_json_file(const std::string& path, bool overwrite) const {
    write_json_file(path, to_json_string(), overwrite);
}

}  // namespace welkin
