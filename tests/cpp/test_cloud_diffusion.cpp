// SPDX-License-Identifier: Apache-2.0
// The delta-Eddington slab of clouds/diffusion.hpp: its closed form against its own
// equations and energy balance, and the fast march's multiple scattering built on it
// against the path-tracing reference on a thick conservative slab.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>

#include "cloud_test_util.hpp"
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "welkin/base/math.hpp"
#include "welkin/clouds/diffusion.hpp"
#include "welkin/clouds/lighting.hpp"
#include "welkin/clouds/reference.hpp"

using namespace welkin;
using welkin::test::HomogeneousBox;

// The solution satisfies its ODE phi'' = k^2 phi - 3 albedo e^{-z/mu0} and dphi/dz = -3 F
// inside (central differences, h = 1e-4: truncation ~1e-8 of phi), and Marshak's face
// conditions phi(0) = -2 F(0), phi(Z) = 2 F(Z) (no diffuse light coming in), to rounding.
TEST(EddingtonSlab, SolvesItsEquationsAndFaceConditions) {
    for (double albedo : {1.0, 0.999, 0.9, 2.0 / 3.0, 0.3})
        for (double mu0 : {1.0, 0.7, 0.25})
            for (double Z : {0.05, 2.0, 30.0}) {
                const double k2 = 3.0 * (1.0 - albedo);
                const DiffuseField top = eddington_slab(Z, 0.0, albedo, mu0),
                                   bot = eddington_slab(Z, Z, albedo, mu0);
                const double scale = std::max({std::abs(top.fluence), std::abs(bot.fluence), 1e-3});
                EXPECT_NEAR(top.fluence, -2.0 * top.flux, 1e-9 * scale) << albedo << " " << mu0 << " " << Z;
                EXPECT_NEAR(bot.fluence, 2.0 * bot.flux, 1e-9 * scale) << albedo << " " << mu0 << " " << Z;
                const double h = 1e-4 * std::max(Z, 1.0) * (Z < 1 ? Z : 1.0);
                for (double f : {0.3, 0.7}) {
                    const double z = f * Z;
                    const DiffuseField a = eddington_slab(Z, z - h, albedo, mu0),
                                       c = eddington_slab(Z, z, albedo, mu0),
                                       b = eddington_slab(Z, z + h, albedo, mu0);
                    const double d2 = (a.fluence - 2.0 * c.fluence + b.fluence) / (h * h);
                    const double rhs = k2 * c.fluence - 3.0 * albedo * std::exp(-z / mu0);
                    EXPECT_NEAR(d2, rhs, 2e-4 * (std::abs(rhs) + 1.0)) << albedo << " " << mu0 << " " << Z;
                    EXPECT_NEAR((b.fluence - a.fluence) / (2.0 * h), -3.0 * c.flux,
                                1e-5 * (std::abs(c.flux) + 1.0));
                }
            }
}

// Energy: what enters (mu0 per unit irradiance normal to the beam) is reflected (-F(0)),
// transmitted (F(Z) + mu0 e^{-Z/mu0}) or absorbed (int (1 - albedo) (phi + e^{-z/mu0}) dz:
// from the diffuse field and from the beam's extinction), exactly for albedo 1 and by a
// 4000-interval midpoint rule otherwise. Deep in a thick conservative slab the
// fluence is the linear diffusion profile phi = 3 F (Z + 2/3 - z).
TEST(EddingtonSlab, ConservesEnergyAndIsLinearDeepInside) {
    for (double mu0 : {1.0, 0.5, 0.2})
        for (double Z : {0.1, 3.0, 40.0}) {
            const DiffuseField top = eddington_slab(Z, 0.0, 1.0, mu0), bot = eddington_slab(Z, Z, 1.0, mu0);
            EXPECT_NEAR(-top.flux + bot.flux + mu0 * std::exp(-Z / mu0), mu0, 1e-12);
            for (double albedo : {0.95, 0.5}) {
                const DiffuseField t = eddington_slab(Z, 0.0, albedo, mu0),
                                   b = eddington_slab(Z, Z, albedo, mu0);
                double absorbed = 0.0;
                const int n = 40000;
                for (int i = 0; i < n; ++i) {
                    const double z = (i + 0.5) * Z / n;
                    const double phi = eddington_slab(Z, z, albedo, mu0).fluence;
                    absorbed += (1.0 - albedo) * (phi + std::exp(-z / mu0)) * Z / n;
                }
                EXPECT_NEAR(-t.flux + b.flux + mu0 * std::exp(-Z / mu0) + absorbed, mu0, 1e-6);
            }
        }
    const double Z = 60.0;
    for (double z : {30.0, 45.0, 59.0}) {  // (up to the beam's terms, O(Z e^{-z}))
        const DiffuseField d = eddington_slab(Z, z, 1.0, 1.0);
        EXPECT_NEAR(d.fluence, 3.0 * d.flux * (Z + 2.0 / 3.0 - z), 1e-9);
    }
    // At normal incidence the transmitted flux is (5/3) / (Z + 4/3) (the header's closed form).
    EXPECT_NEAR(eddington_slab(Z, Z, 1.0, 1.0).flux + std::exp(-Z), (5.0 / 3.0) / (Z + 4.0 / 3.0), 1e-12);
    // Continuous into the conservative branch and across the resonance k mu0 = 1.
    EXPECT_NEAR(eddington_slab(5.0, 2.0, 1.0 - 1e-11, 1.0).fluence,
                eddington_slab(5.0, 2.0, 1.0, 1.0).fluence, 1e-6);
    // (phi moves by ~2e-7 relative for 1e-7 in albedo here: the tolerance is 5 times that)
    const double ar = 1.0 - 1.0 / (3.0 * 0.81);  // k^2 mu0^2 = 1 at mu0 = 0.9
    const double at = eddington_slab(5.0, 2.0, ar, 0.9).fluence;
    EXPECT_GT(at, 0.0);
    EXPECT_NEAR(at, eddington_slab(5.0, 2.0, ar + 1e-7, 0.9).fluence, 1e-6 * at);
    EXPECT_NEAR(at, eddington_slab(5.0, 2.0, ar - 1e-7, 0.9).fluence, 1e-6 * at);
}

// The sides (clouds/diffusion.hpp): with the transverse buckling B^2 the slab still solves
// its ODE, phi'' = (k^2 + B^2) phi - 3 albedo e^{-z/mu0}, and its energy balance gains the
// light leaked through the sides, int (B^2 / 3) phi dz (a 40000-interval midpoint rule):
// for albedo 1, R + T + leaked = mu0. The leak only removes light.
TEST(EddingtonSlab, SidesLeakTheirShareOfTheLight) {
    for (double mu0 : {1.0, 0.5})
        for (double Z : {0.5, 4.0, 30.0})
            for (double leak : {0.01, 0.3, 2.0}) {
                const DiffuseField top = eddington_slab(Z, 0.0, 1.0, mu0, leak),
                                   bot = eddington_slab(Z, Z, 1.0, mu0, leak);
                EXPECT_NEAR(top.fluence, -2.0 * top.flux, 1e-9 * (std::abs(top.fluence) + 1e-3));
                EXPECT_NEAR(bot.fluence, 2.0 * bot.flux, 1e-9 * (std::abs(bot.fluence) + 1e-3));
                double leaked = 0.0;
                const int n = 40000;
                for (int i = 0; i < n; ++i) {
                    const double z = (i + 0.5) * Z / n;
                    const double phi = eddington_slab(Z, z, 1.0, mu0, leak).fluence;
                    EXPECT_LE(phi, eddington_slab(Z, z, 1.0, mu0).fluence + 1e-12) << Z << " " << leak;
                    leaked += leak / 3.0 * phi * Z / n;
                }
                EXPECT_NEAR(-top.flux + bot.flux + mu0 * std::exp(-Z / mu0) + leaked, mu0, 1e-6)
                    << mu0 << " " << Z << " " << leak;
                const double h = 1e-4, z = 0.4 * Z;
                const DiffuseField a = eddington_slab(Z, z - h, 1.0, mu0, leak),
                                   c = eddington_slab(Z, z, 1.0, mu0, leak),
                                   b = eddington_slab(Z, z + h, 1.0, mu0, leak);
                const double rhs = leak * c.fluence - 3.0 * std::exp(-z / mu0);
                EXPECT_NEAR((a.fluence - 2.0 * c.fluence + b.fluence) / (h * h), rhs,
                            2e-4 * (std::abs(rhs) + 1.0));
            }
}

// The source with sides: an infinite chord is the slab; a wide cloud (chord 1e9) is the
// slab to rounding; deep in a cloud the source falls as the chord narrows; at the lit face
// the higher modes hold the slab's value (the blend's weight is 1 there).
TEST(CloudDiffusion, SidesVanishForWideCloudsAndDarkenNarrowOnes) {
    const SimilarityScaling sim(1.0, 0.85);
    const double nu = 0.2, p = 0.1, p2 = 0.12, inf = std::numeric_limits<double>::infinity();
    for (double ts : {0.0, 3.0, 30.0}) {
        const double slab = sun_source(sim, ts, 20.0, inf, nu, 0.85, p, p2);
        EXPECT_NEAR(sun_source(sim, ts, 20.0, 1e9, nu, 0.85, p, p2), slab, 1e-9 * slab);
    }
    double last = sun_source(sim, 30.0, 20.0, inf, nu, 0.85, p, p2);
    for (double chord : {1e3, 100.0, 30.0, 10.0, 3.0}) {
        const double v = sun_source(sim, 30.0, 20.0, chord, nu, 0.85, p, p2);
        EXPECT_LT(v, last) << chord;
        last = v;
    }
    EXPECT_NEAR(sun_source(sim, 0.0, 20.0, 3.0, nu, 0.85, p, p2),
                sun_source(sim, 0.0, 20.0, inf, nu, 0.85, p, p2), 1e-12);
}

// A thick conservative slab (tau = 16 vertically, wide enough to be infinite), lit by the
// sun alone, views from below (transmitted light) and from above (reflected light): the
// fast march against the path-tracing reference (all orders). The sun stands at
// sin(elevation) = 2/3: there a horizontal slab's Eddington escape factor 1/2 + 3 mu0 / 4
// is 1, its orientation average (clouds/diffusion.hpp), so deep in the slab the model's
// assumption about the unknown surface orientation holds. What is left:
//  * the delta-Eddington error (Joseph, Wiscombe & Weinman 1976: fluxes within ~10 % for
//    thick conservative slabs);
//  * at this finite thickness (scaled T' = 10 along the sun line) the orientation average
//    includes steep slabs (small mu0) whose extrapolation lengths 4 / (3 mu0) thin the
//    light: transmitted light comes out low;
//  * the model's mean flux runs along the sun line, a slab's along its normal: the view
//    dependence differs (the reference below is nearly isotropic, 0.044 / 0.041 / 0.040;
//    the march 0.036 / 0.039 / 0.031, brighter towards the sun).
// Measured (40000 paths, se 2.6 % per view): the mean over the three views below -16 %,
// above -6 %. Tolerances on those means: below within [-25 %, +10 %], above within +-12 %
// (the delta-Eddington 10 % plus the reflected light's single scattering, exact), each
// plus 4 standard errors of the reference's mean; per view within 30 %. Wrenninge's
// octaves on the same slab give 2 % of the transmitted light (they decay as exp(-tau / 8)):
// the test fails for a march without the diffusion term.
TEST(CloudDiffusion, ThickConservativeSlabAgainstReference) {
    const double sigma = 0.02, D = 800.0;  // tau = 16
    const HomogeneousBox slab({-1e6, -1e6, 0.0}, {1e6, 1e6, D}, sigma);
    const double sin_e = 2.0 / 3.0, cos_e = std::sqrt(1.0 - sin_e * sin_e);
    const ConstantIllumination light({cos_e, 0.0, sin_e}, {1.0f, 1.0f, 1.0f}, {0.0f, 0.0f, 0.0f});
    const std::vector<glm::dvec3> up = {
        {0, 0, 1}, glm::normalize(glm::dvec3(0.5, 0.2, 1.0)), glm::normalize(glm::dvec3(-0.6, 0.0, 1.0))};
    std::vector<glm::dvec3> down;
    for (const auto& d : up) down.push_back({d.x, d.y, -d.z});
    CloudLightingOptions o;
    o.light_distance_m = 4000.0;  // the sun line crosses the slab in 1200 m
    CloudLightingOptions oct = o;
    oct.multiple_scattering = CloudMultipleScattering::octaves;
    CloudReferenceOptions ro;
    ro.paths = 40000;
    for (const auto& [name, eye, dirs] : {std::tuple{"below", glm::dvec3(0, 0, -50), up},
                                          std::tuple{"above", glm::dvec3(0, 0, D + 50), down}}) {
        const bool below = std::string(name) == "below";
        const CloudResult fast = render_clouds(slab, light, eye, dirs, o);
        const CloudResult octaves = render_clouds(slab, light, eye, dirs, oct);
        const CloudReferenceResult ref = render_clouds_reference(slab, light, eye, dirs, ro);
        double sf = 0.0, sr = 0.0, var = 0.0;
        for (std::size_t r = 0; r < dirs.size(); ++r) {
            const double lf = fast.radiance[r * 3 + 1], lr = ref.radiance[r * 3 + 1];
            const double se = ref.radiance_error[r * 3 + 1];
            std::printf(
                "slab %s, view %zu: fast %.5g, octaves %.5g, reference %.5g +- %.2g (fast %+.1f %%)\n", name,
                r, lf, octaves.radiance[r * 3 + 1], lr, se, 100.0 * (lf / lr - 1.0));
            EXPECT_NEAR(lf, lr, 0.30 * lr + 4.0 * se) << name << " view " << r;
            if (below) {
                EXPECT_LT(octaves.radiance[r * 3 + 1], 0.5 * lr);
            }
            sf += lf;
            sr += lr;
            var += se * se;
        }
        const double bias = sf / sr - 1.0, se_rel = std::sqrt(var) / sr;
        std::printf("slab %s: mean of the views fast %+.1f %% (reference se %.1f %%)\n", name, 100.0 * bias,
                    100.0 * se_rel);
        EXPECT_GT(bias, (below ? -0.25 : -0.12) - 4.0 * se_rel) << name;
        EXPECT_LT(bias, (below ? 0.10 : 0.12) + 4.0 * se_rel) << name;
    }
}
