// SPDX-License-Identifier: Apache-2.0
// Atmosphere parameters: presets, validation, JSON round trip.
#include <cmath>

#include "peer_table.hpp"
#include <gtest/gtest.h>

#include "welkin/atmosphere/atmosphere.hpp"
#include "welkin/base/error.hpp"

using namespace welkin;

TEST(Atmosphere, Bruneton2017PresetMatchesPeerParameters) {
    // tests/data/README.md: the peer's coefficients at 680/550/440 nm.
    const Atmosphere a = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    ASSERT_EQ(a.channels(), 3u);
    const double rayleigh[] = {5.802e-6, 13.558e-6, 33.1e-6};
    const double ozone[] = {0.650e-6, 1.881e-6, 0.085e-6};
    const double solar[] = {1.474, 1.8504, 1.91198};
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(a.rayleigh_scattering[c] / rayleigh[c], 1.0, 1e-3);
        EXPECT_NEAR(a.absorption_extinction[c] / ozone[c], 1.0, 3e-3);
        EXPECT_NEAR(a.solar_irradiance[c], solar[c], 1e-9);
        EXPECT_NEAR(a.mie_extinction[c], 4.44e-6, 1e-12);
        EXPECT_NEAR(a.mie_scattering[c], 3.996e-6, 1e-12);
        EXPECT_DOUBLE_EQ(a.ground_albedo[c], 0.1);
    }
    EXPECT_DOUBLE_EQ(a.mie_g, 0.8);
    EXPECT_EQ(a.mie_phase, MiePhaseModel::CornetteShanks);
    EXPECT_DOUBLE_EQ(a.bottom_radius_m, 6360e3);
    EXPECT_DOUBLE_EQ(a.top_radius_m, 6420e3);
    // Ozone tent: 0 at 10 km, 1 at 25 km, 0 at 40 km.
    EXPECT_NEAR(a.absorption_density.density(10e3), 0.0, 1e-12);
    EXPECT_NEAR(a.absorption_density.density(25e3), 1.0, 1e-12);
    EXPECT_NEAR(a.absorption_density.density(40e3), 0.0, 1e-12);
    EXPECT_NEAR(a.absorption_density.density(17.5e3), 0.5, 1e-12);
    EXPECT_NEAR(a.rayleigh_density.density(8000.0), std::exp(-1.0), 1e-12);
}

TEST(Atmosphere, EveryPresetValidatesAtDefaultAndSpectralWavelengths) {
    for (const std::string& name : Atmosphere::preset_names()) {
        EXPECT_NO_THROW(Atmosphere::preset(name)) << name;
        EXPECT_EQ(Atmosphere::preset(name, spectral_wavelengths_nm()).channels(), 48u) << name;
    }
}

TEST(Atmosphere, UnknownPresetNamesTheChoices) {
    try {
        Atmosphere::preset("earthish");
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "preset");
        EXPECT_NE(std::string(e.what()).find("bruneton2017"), std::string::npos);
    }
}

TEST(Atmosphere, ValidationNamesTheParameterAndRange) {
    auto expect_param = [](Atmosphere a, const std::string& param) {
        try {
            a.validate();
            ADD_FAILURE() << "no error for " << param;
        } catch (const InvalidArgument& e) {
            EXPECT_EQ(e.parameter(), param) << e.what();
        }
    };
    Atmosphere a = Atmosphere::preset("bruneton2017", test::kPeerWavelengthsNm);
    Atmosphere b = a;
    b.bottom_radius_m = -5.0;
    expect_param(b, "bottom_radius_m");
    b = a;
    b.top_radius_m = a.bottom_radius_m - 1.0;  // inverted
    expect_param(b, "top_radius_m");
    b = a;
    b.mie_g = 1.0;
    expect_param(b, "mie.g");
    b = a;
    b.rayleigh_scattering[1] = std::nan("");
    expect_param(b, "rayleigh.scattering[1]");
    b = a;
    b.mie_scattering[0] = 2.0 * b.mie_extinction[0];
    expect_param(b, "mie.scattering[0]");
    b = a;
    b.ground_albedo.pop_back();
    expect_param(b, "ground_albedo");
}

TEST(Atmosphere, JsonRoundTripIsExact) {
    const Atmosphere a = Atmosphere::preset("mars");
    const Atmosphere b = Atmosphere::from_json_string(a.to_json_string());
    EXPECT_EQ(a.to_json_string(), b.to_json_string());
    EXPECT_EQ(b.name, "mars");
}

TEST(Atmosphere, JsonPresetWithOverrides) {
    const Atmosphere a = Atmosphere::from_json_string(
        R"({"preset": "bruneton2017", "mie": {"g": 0.5, "phase": "henyey_greenstein"},
            "ground_albedo": 0.3})");
    EXPECT_DOUBLE_EQ(a.mie_g, 0.5);
    EXPECT_EQ(a.mie_phase, MiePhaseModel::HenyeyGreenstein);
    EXPECT_DOUBLE_EQ(a.ground_albedo[2], 0.3);
}

TEST(Atmosphere, MalformedJsonIsAClearError) {
    EXPECT_THROW(Atmosphere::from_json_string("{\"preset\": \"clear\","), InvalidArgument);
    try {
        Atmosphere::from_json_string(R"({"preset": "clear", "mie": {"gg": 0.5}})");
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "mie.gg");
    }
    try {
        Atmosphere::from_json_string(R"({"preset": "clear", "top_radius_m": "high"})");
        FAIL();
    } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.parameter(), "top_radius_m");
    }
}
