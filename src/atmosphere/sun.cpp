// SPDX-License-Identifier: Apache-2.0
// The sun seen from the observer; see sun.hpp.
#include "welkin/atmosphere/sun.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "welkin/atmosphere/geometry.hpp"
#include "welkin/atmosphere/optical_depth.hpp"
#include "welkin/base/error.hpp"
#include "welkin/base/math.hpp"

namespace welkin {
namespace {

// Limb darkening, Neckel & Labs 1994 ("The solar radiation between 3300 and 12500 A",
// Solar Physics 153, 91-114), their fifth-order fits of the centre-to-limb variation at
// 30 continuum windows:
//     I(lambda, mu) / I(lambda, 1) = sum_{k=0..5} a_k(lambda) mu^k,
// mu = cos(heliocentric angle). Columns: wavelength (nm), a0 .. a5. The coefficients of
// each row sum to 1 (mu = 1); the paper's ratio of mean to central intensity,
// 2 sum a_k / (k + 2), is checked row by row in tests/cpp/test_sun.cpp. In the 365.875 nm
// row, a2 = 0.17682: the copy we had read 0.17482, which breaks both the sum (0.998) and
// the tabulated mean ratio (0.7445); changing that one digit restores both exactly.
// Between rows the coefficients are interpolated linearly in wavelength; outside
// [303, 1099] nm the end rows apply.
struct LimbRow {
    double wavelength_nm;
    std::array<double, 6> a;
};
constexpr std::array<LimbRow, 30> kNeckelLabs1994 = {{
    {303.327, {0.08011, 0.70695, 0.49910, -0.31080, -0.02177, 0.04642}},
    {310.843, {0.08160, 0.71609, 0.69685, -0.87703, 0.47008, -0.08760}},
    {320.468, {0.08833, 0.77285, 0.65382, -1.04647, 0.72921, -0.19775}},
    {329.897, {0.09188, 0.92459, 0.19604, -0.39546, 0.23599, -0.05303}},
    {349.947, {0.11012, 1.02168, -0.10924, -0.00055, -0.08688, 0.06487}},
    {365.875, {0.12828, 1.04969, 0.17682, -1.13371, 1.23882, -0.45990}},
    {374.086, {0.12579, 0.85402, 0.54601, -1.15048, 0.88928, -0.26462}},
    {390.915, {0.12995, 0.91836, -0.07566, 0.19149, -0.28712, 0.12298}},
    {401.970, {0.12323, 1.08648, -0.43974, 0.45912, -0.32759, 0.09850}},
    {416.319, {0.12814, 1.19947, -0.84407, 1.07201, -0.79537, 0.23982}},
    {427.930, {0.14249, 1.28796, -1.19564, 1.68603, -1.36658, 0.44572}},
    {443.885, {0.16220, 1.24893, -0.92165, 0.89978, -0.50148, 0.11220}},
    {445.125, {0.15248, 1.38517, -1.49615, 1.99886, -1.48155, 0.44119}},
    {457.345, {0.16604, 1.38544, -1.52275, 2.00232, -1.45969, 0.42864}},
    {477.427, {0.19571, 1.30551, -1.25845, 1.50626, -1.05472, 0.30570}},
    {492.905, {0.20924, 1.30798, -1.20411, 1.21505, -0.67196, 0.14381}},
    {519.930, {0.23695, 1.29927, -1.28034, 1.37760, -0.85054, 0.21706}},
    {541.760, {0.26073, 1.27428, -1.30352, 1.47085, -0.96618, 0.26384}},
    {559.950, {0.26892, 1.34319, -1.58427, 1.91271, -1.31350, 0.37295}},
    {579.880, {0.28392, 1.36896, -1.75998, 2.22154, -1.56074, 0.44630}},
    {610.975, {0.30854, 1.36620, -1.83572, 2.33221, -1.63082, 0.45959}},
    {640.970, {0.33644, 1.30590, -1.79238, 2.45040, -1.89979, 0.59943}},
    {669.400, {0.34685, 1.37539, -2.04425, 2.70493, -1.94290, 0.55999}},
    {700.875, {0.37885, 1.25553, -1.70908, 2.19647, -1.59554, 0.47378}},
    {748.710, {0.40627, 1.22842, -1.67877, 2.05535, -1.39972, 0.38845}},
    {811.760, {0.42977, 1.25182, -1.85164, 2.31949, -1.59101, 0.44155}},
    {869.600, {0.45396, 1.25101, -2.02958, 2.75410, -2.02287, 0.59338}},
    {948.850, {0.47855, 1.19813, -1.86296, 2.36939, -1.64367, 0.46056}},
    {1046.60, {0.49870, 1.21429, -2.06976, 2.80703, -2.05247, 0.60221}},
    {1098.95, {0.51149, 1.19354, -2.00174, 2.66936, -1.94981, 0.57715}},
}};

}  // namespace

std::array<double, 6> limb_darkening_coefficients(double wavelength_nm) {
    const auto& t = kNeckelLabs1994;
    if (!(wavelength_nm > t.front().wavelength_nm)) return t.front().a;
    if (wavelength_nm >= t.back().wavelength_nm) return t.back().a;
    std::size_t i = 0;
    while (t[i + 1].wavelength_nm <= wavelength_nm) ++i;
    const double f = (wavelength_nm - t[i].wavelength_nm) / (t[i + 1].wavelength_nm - t[i].wavelength_nm);
    std::array<double, 6> a;
    for (int k = 0; k < 6; ++k) a[k] = t[i].a[k] * (1.0 - f) + t[i + 1].a[k] * f;
    return a;
}

namespace {

double polynomial(const double* a, double mu) {
    return a[0] + mu * (a[1] + mu * (a[2] + mu * (a[3] + mu * (a[4] + mu * a[5]))));
}

// 8-point Gauss-Legendre on [0, 1] (Abramowitz & Stegun 25.4.30, mapped).
constexpr std::array<double, 4> kNodes = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                          0.9602898564975363};
constexpr std::array<double, 4> kWeights = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                            0.1012285362903763};

// Area of the part of a unit disc above a chord at signed distance x from its centre
// (x > 0: the centre is above the chord), as a fraction of the disc: the circular
// segment below the chord has area acos(x) - x sqrt(1 - x^2) (radius 1).
double disc_fraction_above_chord(double x) {
    x = std::clamp(x, -1.0, 1.0);
    return clamp01(1.0 - (std::acos(x) - x * std::sqrt(1.0 - x * x)) / kPi);
}

}  // namespace

// A point at angular distance rho from the centre of a disc of angular radius alpha lies,
// seen from the sun's centre, at heliocentric angle theta with sin theta =
// sin rho / sin alpha (the sphere is seen in exact perspective; for the sun's 0.27
// degrees this is the orthographic projection to 1e-5). mu = cos theta.
//
// Normalisation: the mean of P(mu) = sum a_k mu^k over the disc's solid angle. With
// s = sin rho / sin alpha, dOmega = 2 pi sin rho d rho = 2 pi sin^2 alpha s ds / cos rho and
// cos rho = sqrt(1 - s^2 sin^2 alpha); substituting mu = sqrt(1 - s^2) (s ds = -mu dmu),
//     integral of P over the disc = 2 pi sin^2 alpha int_0^1 P(mu) mu w(mu) dmu,
//     w(mu) = 1 / sqrt(1 - (1 - mu^2) sin^2 alpha),
// and the disc's solid angle is the same with P = 1, 2 pi (1 - cos alpha). The integrand
// is a polynomial times a weight within 2 % of 1 (alpha <= 0.2 rad), so 8-point
// Gauss-Legendre is exact to ~1e-12. For alpha -> 0 the mean tends to Neckel & Labs'
// 2 sum a_k / (k + 2).
LimbDarkening::LimbDarkening(double radius_rad, double wavelength_nm)
    : radius_rad_(radius_rad), sin_radius_(std::sin(radius_rad)) {
    require_in_range("sun_angular_radius_rad", radius_rad, 1e-6, 0.5 * kPi, "rad");
    require_in_range("wavelength_nm", wavelength_nm, 1.0, 1e5, "nm");
    const std::array<double, 6> a = limb_darkening_coefficients(wavelength_nm);
    std::copy(a.begin(), a.end(), a_);
    coefficients_sum_ = polynomial(a_, 1.0);
    const double s2 = sin_radius_ * sin_radius_;
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < kNodes.size(); ++i)
        for (double mu : {0.5 * (1.0 - kNodes[i]), 0.5 * (1.0 + kNodes[i])}) {
            const double w = 0.5 * kWeights[i] * mu / std::sqrt(1.0 - (1.0 - mu * mu) * s2);
            num += w * polynomial(a_, mu);
            den += w;
        }
    mean_ = num / den;
}

double LimbDarkening::operator()(double angle_rad) const {
    if (!(angle_rad <= radius_rad_) || angle_rad < 0.0) return 0.0;
    const double s = std::min(1.0, std::sin(angle_rad) / sin_radius_);
    const double mu = safe_sqrt(1.0 - s * s);
    return std::max(0.0, polynomial(a_, mu)) / mean_;
}

double limb_darkening(double angle_rad, double radius_rad, double wavelength_nm) {
    return LimbDarkening(radius_rad, wavelength_nm)(angle_rad);
}

// Direct sunlight at the observer.
//
// The observer stands at r = bottom_radius + altitude on the Z axis, so the sun's zenith
// cosine is mu_s = sun_direction.z. The ground sphere hides everything below the horizon
// elevation e_h = -acos(R / r) (the tangent ray, e_h = 0 on the ground). The disc, of
// angular radius alpha, has its centre at elevation e_s; the horizon crosses it as a chord
// at distance (e_s - e_h) from the centre (the horizon's curvature across a 0.5 degree
// disc is negligible), which leaves the fraction of the disc's area given by the circular
// segment formula above.
//
// Transmittance is the exact quadrature of optical_depth.hpp along one ray: through the
// disc centre when the disc is whole; when the horizon cuts it, through the middle of the
// visible part's vertical extent [e_h, e_s + alpha] (a ray through a centre that is
// already below the horizon would hit the ground; one that grazes the horizon would be
// far too dark for the visible cap). The two choices agree when the chord touches the
// disc's bottom edge, so the result is continuous in e_s. Bruneton 2017
// (GetTransmittanceToSun) makes the same correction with a smoothstep on the fraction.
SunRadiometry sun_radiometry(const Atmosphere& atm, const Observer& observer) {
    atm.validate();
    const Observer o = observer.validated();
    const std::size_t n = atm.channels();
    const double R = atm.bottom_radius_m;
    const double r = R + o.altitude_m;
    const double alpha = atm.sun_angular_radius_rad;

    const double e_s = std::asin(clamp_cosine(o.sun_direction.z));
    // sin e_h = -sqrt(r^2 - R^2) / r, written without cancellation.
    const double e_h = -std::asin(std::min(1.0, safe_sqrt((r - R) * (r + R)) / r));
    const double x = (e_s - e_h) / alpha;

    SunRadiometry out;
    out.visible_fraction = disc_fraction_above_chord(x);
    out.transmittance.assign(n, 0.0);
    out.direct_irradiance.assign(n, 0.0);
    if (out.visible_fraction <= 0.0) return out;

    const double e_eval = x >= 1.0 ? e_s : 0.5 * (e_h + e_s + alpha);
    const double mu = clamp_cosine(std::sin(e_eval));
    out.transmittance = transmittance_to_boundary(atm, r, mu, /*ground_blocks=*/true);
    for (std::size_t c = 0; c < n; ++c)
        out.direct_irradiance[c] = atm.solar_irradiance[c] * out.transmittance[c] * out.visible_fraction;
    return out;
}

}  // namespace welkin
