// SPDX-License-Identifier: Apache-2.0
// Phase functions (phase.hpp) and the reference path tracer's sampling routines
// (atmosphere/phase_sampling.hpp, base/rng.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "welkin/atmosphere/phase.hpp"
#include "welkin/atmosphere/phase_sampling.hpp"
#include "welkin/base/rng.hpp"

using namespace welkin;

namespace {

// int_-1^1 f(nu) dnu by 8-point Gauss-Legendre on panels graded as (i / n)^3 towards nu = 1,
// where forward-peaked phase functions are sharp (width ~(1 - g)^2 / 2g).
double integrate_cosine(const std::function<double(double)>& f, int n = 400) {
    static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                0.9602898564975363};
    static const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                0.1012285362903763};
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double a = 1.0 - 2.0 * std::pow(double(i + 1) / n, 3.0);
        const double b = 1.0 - 2.0 * std::pow(double(i) / n, 3.0);
        const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
        for (int k = 0; k < 4; ++k) sum += half * w[k] * (f(mid - half * x[k]) + f(mid + half * x[k]));
    }
    return sum;
}

// Solid-angle integral of an axially symmetric p(nu): 2 pi int p dnu.
double sphere_integral(const std::function<double(double)>& p) { return kTwoPi * integrate_cosine(p); }

double hg_cdf(double nu, double g) {
    return (1.0 - g * g) / (2.0 * g) * (1.0 / std::sqrt(1.0 + g * g - 2.0 * g * nu) - 1.0 / (1.0 + g));
}
double rayleigh_cdf(double nu) { return (nu * nu * nu + 3.0 * nu + 4.0) / 8.0; }

// Kolmogorov-Smirnov distance between samples and a CDF.
double ks_distance(std::vector<double> samples, const std::function<double(double)>& cdf) {
    std::sort(samples.begin(), samples.end());
    const double n = double(samples.size());
    double d = 0.0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
        const double f = cdf(samples[i]);
        d = std::max({d, std::abs(f - double(i) / n), std::abs(f - double(i + 1) / n)});
    }
    return d;
}

}  // namespace

TEST(Phase, EveryPhaseFunctionIntegratesToOneOverTheSphere) {
    EXPECT_NEAR(sphere_integral([](double nu) { return rayleigh_phase(nu); }), 1.0, 1e-12);
    for (double g : {-0.5, 0.0, 0.3, 0.8, 0.95}) {
        EXPECT_NEAR(sphere_integral([g](double nu) { return henyey_greenstein_phase(nu, g); }), 1.0, 1e-9)
            << g;
        EXPECT_NEAR(sphere_integral([g](double nu) { return cornette_shanks_phase(nu, g); }), 1.0, 1e-9) << g;
    }
    EXPECT_NEAR(sphere_integral([](double) { return kIsotropicPhase; }), 1.0, 1e-12);
}

TEST(Phase, MeanCosinesMatchClosedForms) {
    // HG's asymmetry parameter is its mean cosine; Cornette-Shanks' is
    // 3 g (g^2 + 4) / (5 (g^2 + 2)); Rayleigh's is 0.
    for (double g : {-0.5, 0.3, 0.8, 0.95}) {
        EXPECT_NEAR(sphere_integral([g](double nu) { return nu * henyey_greenstein_phase(nu, g); }), g, 1e-9);
        EXPECT_NEAR(sphere_integral([g](double nu) { return nu * cornette_shanks_phase(nu, g); }),
                    3.0 * g * (g * g + 4.0) / (5.0 * (g * g + 2.0)), 1e-9);
    }
    EXPECT_NEAR(sphere_integral([](double nu) { return nu * rayleigh_phase(nu); }), 0.0, 1e-12);
}

// The Legendre moments chi_l = 2 pi int p P_l dnu used by the multiple-scattering LUT:
// the closed forms of phase.hpp against direct quadrature, for l = 0, 1, 2.
TEST(Phase, LegendreMomentsMatchQuadrature) {
    const auto legendre = [](int l, double nu) {
        return l == 0 ? 1.0 : l == 1 ? nu : 0.5 * (3.0 * nu * nu - 1.0);
    };
    for (int l = 0; l <= 2; ++l) {
        EXPECT_NEAR(rayleigh_phase_moment(l),
                    sphere_integral([&](double nu) { return rayleigh_phase(nu) * legendre(l, nu); }), 1e-12)
            << l;
        for (double g : {-0.5, 0.0, 0.3, 0.8, 0.95}) {
            EXPECT_NEAR(
                mie_phase_moment(MiePhaseModel::HenyeyGreenstein, l, g),
                sphere_integral([&](double nu) { return henyey_greenstein_phase(nu, g) * legendre(l, nu); }),
                1e-9)
                << "HG l " << l << " g " << g;
            EXPECT_NEAR(
                mie_phase_moment(MiePhaseModel::CornetteShanks, l, g),
                sphere_integral([&](double nu) { return cornette_shanks_phase(nu, g) * legendre(l, nu); }),
                1e-9)
                << "CS l " << l << " g " << g;
        }
    }
}

TEST(PhaseSampling, SamplersInvertTheirCdfs) {
    // sample_rayleigh_cosine is F^-1 with F(nu) = (nu^3 + 3 nu + 4) / 8; the HG sampler is
    // F^-1(1 - u), which is as uniform.
    for (int i = 0; i <= 1000; ++i) {
        const double u = i / 1000.0;
        EXPECT_NEAR(rayleigh_cdf(sample_rayleigh_cosine(u)), u, 1e-12) << u;
        for (double g : {-0.5, 0.3, 0.8, 0.95})
            EXPECT_NEAR(hg_cdf(sample_henyey_greenstein_cosine(u, g), g), 1.0 - u, 1e-9) << u << " " << g;
    }
}

TEST(PhaseSampling, SampledDistributionsMatch) {
    // Random samples: Kolmogorov-Smirnov distance below the 1 % critical value 1.63/sqrt(n),
    // and the sample mean cosine equal to g (HG) within 5 standard errors; the tracer's
    // Cornette-Shanks estimator (HG samples weighted by p_CS / p_HG) gives CS's mean cosine.
    const int n = 200000;
    PathRng rng(2024, 0, 0);
    std::vector<double> rayleigh(n);
    for (double& x : rayleigh) x = sample_rayleigh_cosine(rng.uniform());
    EXPECT_LT(ks_distance(rayleigh, rayleigh_cdf), 1.63 / std::sqrt(double(n)));
    double mean_sq = 0.0;
    for (double x : rayleigh) mean_sq += x * x / n;
    EXPECT_NEAR(mean_sq, 0.4, 5.0 * 0.34 / std::sqrt(double(n)));  // E[nu^2] = 2/5

    for (double g : {0.3, 0.8, 0.95}) {
        std::vector<double> hg(n);
        double mean = 0.0, mean2 = 0.0, cs_mean = 0.0;
        for (double& x : hg) {
            x = sample_henyey_greenstein_cosine(rng.uniform(), g);
            mean += x / n;
            mean2 += x * x / n;
            cs_mean += x * cornette_shanks_phase(x, g) / henyey_greenstein_phase(x, g) / n;
        }
        const double se = std::sqrt((mean2 - mean * mean) / n);
        EXPECT_NEAR(mean, g, 5.0 * se) << g;
        EXPECT_NEAR(cs_mean, 3.0 * g * (g * g + 4.0) / (5.0 * (g * g + 2.0)), 5.0 * 1.2 * se) << g;
        EXPECT_LT(ks_distance(hg, [g](double nu) { return hg_cdf(nu, g); }), 1.63 / std::sqrt(double(n)))
            << g;
    }
}

TEST(PhaseSampling, DirectionsAboutAnAxisHaveTheRequestedCosineAndUniformAzimuth) {
    PathRng rng(3, 0, 0);
    for (const glm::dvec3 axis :
         {glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1), glm::normalize(glm::dvec3(0.3, -0.8, 0.2))}) {
        glm::dvec3 t, b;
        orthonormal_basis(axis, t, b);
        EXPECT_NEAR(glm::dot(t, axis), 0.0, 1e-12);
        EXPECT_NEAR(glm::dot(b, axis), 0.0, 1e-12);
        EXPECT_NEAR(glm::dot(t, b), 0.0, 1e-12);
        EXPECT_NEAR(glm::length(t), 1.0, 1e-12);
        glm::dvec3 mean_perp(0.0);
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            const double c = 2.0 * rng.uniform() - 1.0;
            const glm::dvec3 d = direction_about(axis, c, rng.uniform());
            EXPECT_NEAR(glm::length(d), 1.0, 1e-12);
            EXPECT_NEAR(glm::dot(d, axis), c, 1e-12);
            mean_perp += (d - glm::dot(d, axis) * axis) / double(n);
        }
        // Perpendicular part averages to 0 (sd per sample <= 1).
        EXPECT_LT(glm::length(mean_perp), 5.0 / std::sqrt(double(n)));
    }
    // Lambertian hemisphere: mean cosine 2/3 (E[cos] of density cos/pi), never below.
    const glm::dvec3 n(0.6, 0.0, 0.8);
    double mean = 0.0;
    for (int i = 0; i < 100000; ++i) {
        const double c = glm::dot(sample_cosine_hemisphere(n, rng.uniform(), rng.uniform()), n);
        EXPECT_GE(c, 0.0);
        mean += c / 100000.0;
    }
    EXPECT_NEAR(mean, 2.0 / 3.0, 5.0 * 0.236 / std::sqrt(100000.0));  // sd of cos = sqrt(1/18)
}

TEST(PathRngTest, StreamsAreDeterministicAndDistinct) {
    PathRng a(1, 2, 3), b(1, 2, 3), c(1, 2, 4), d(2, 2, 3);
    double mean = 0.0;
    for (int i = 0; i < 100000; ++i) {
        const double x = a.uniform();
        EXPECT_EQ(x, b.uniform());
        EXPECT_GE(x, 0.0);
        EXPECT_LT(x, 1.0);
        mean += x / 100000.0;
    }
    EXPECT_NE(c.uniform(), d.uniform());
    EXPECT_NEAR(mean, 0.5, 5.0 * 0.2887 / std::sqrt(100000.0));
}

TEST(QmcSamplerTest, EachPairIsAStratifiedNetAndEachPointIsUniform) {
    // n = 256 points of one batch: every pair of dimensions puts exactly one point in each
    // elementary interval of area 1/256 (shapes 1x1/256, 1/2x1/128, ..., 1/256x1).
    const int m = 8, n = 1 << m;
    for (std::uint64_t key : {1ull, 99ull}) {
        std::vector<std::array<double, QmcSampler::kDimensions>> pts(n);
        for (int i = 0; i < n; ++i) {
            PathRng rng(5, 0, std::uint64_t(i));
            QmcSampler s(key, std::uint32_t(i), rng);
            for (double& x : pts[std::size_t(i)]) {
                x = s.next();
                ASSERT_GE(x, 0.0);
                ASSERT_LT(x, 1.0);
            }
        }
        for (int pair = 0; pair < QmcSampler::kDimensions / 2; ++pair)
            for (int bx = 0; bx <= m; ++bx) {
                const int nx = 1 << bx, ny = n / nx;
                std::set<int> cells;
                for (const auto& p : pts)
                    cells.insert(int(p[std::size_t(2 * pair)] * nx) * ny +
                                 int(p[std::size_t(2 * pair + 1)] * ny));
                EXPECT_EQ(int(cells.size()), n) << "pair " << pair << " shape " << nx << "x" << ny;
            }
    }
    // One point over many batches (random scrambling seeds) is uniform: its mean is 1/2.
    double mean = 0.0;
    const int batches = 40000;
    for (int b = 0; b < batches; ++b) {
        PathRng rng(6, 0, std::uint64_t(b));
        QmcSampler s(splitmix64_mix(std::uint64_t(b)), 7, rng);
        s.skip(3);
        mean += s.next() / batches;
    }
    EXPECT_NEAR(mean, 0.5, 5.0 * 0.2887 / std::sqrt(double(batches)));
}
