// SPDX-License-Identifier: Apache-2.0
#include "welkin/atmosphere/skyview_lut.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "welkin/atmosphere/inscattering.hpp"

namespace welkin {

namespace {

// The upper half's rows (j < h/2) in Hillaire's variable s = 1 - sqrt(1 - theta / theta_h)
// (theta = theta_h (1 - (1 - s)^2), header), spread evenly from the zenith, s = 0 at row 0,
// to s_last = 1 - 1/h at row h/2 - 1 (theta_h (1 - 1/h^2): just above the horizon). Row 0
// is the zenith itself, where every azimuth is one direction: a lookup at the zenith reads
// it exactly rather than a ring of texel centres half a row from it (Hillaire's texel
// centres, s = (2j + 1)/h, put the first row 1.7 degrees from the zenith at h = 108, and a
// zenith lookup clamps to that ring, in the sun's azimuth).
double upper_row_s(int j, int h) { return double(j) * (1.0 - 1.0 / double(h)) / double(h / 2 - 1); }

}  // namespace

SkyViewLut::SkyViewLut(const AtmosphereBatch& batch, const TransmittanceLut& tlut,
                       const MultiScatteringLut& mslut, double r, double mu_s, int width, int height,
                       int steps)
    : r_(r), texture_(width, height) {
    const double R = batch.bottom_radius();
    const double rho = safe_sqrt((r - R) * (r + R));
    beta_ = std::acos(clamp_cosine(rho / r));
    theta_h_ = kPi - beta_;
    const double sin_s = safe_sqrt(1.0 - mu_s * mu_s);
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        // Everything along the ray but the sun is shared by the whole row.
        RaySamples ray;
        InscatterRowScratch scratch;
        std::vector<float> nu(static_cast<std::size_t>(width));
        for (int j = rows.begin(); j != rows.end(); ++j) {
            const double v = (double(j) + 0.5) / double(height);
            double theta;
            if (v < 0.5) {
                const double c = 1.0 - upper_row_s(j, height);
                theta = theta_h_ * (1.0 - c * c);
            } else {
                const double c = 2.0 * v - 1.0;
                theta = theta_h_ + beta_ * c * c;
            }
            const double mu = std::cos(theta), sin_v = std::sin(theta);
            prepare_ray(batch, r, mu, steps, ray, &tlut);
            for (int i = 0; i < width; ++i) {
                const double u = (double(i) + 0.5) / double(width);
                const double cos_phi = 1.0 - 2.0 * u * u;
                nu[std::size_t(i)] = float(clamp_cosine(mu * mu_s + sin_v * sin_s * cos_phi));
            }
            inscatter_row(batch, mslut, ray, mu_s, nu,
                          std::span<Spectrum4>(&texture_.at(0, j), std::size_t(width)), scratch);
        }
    });
    // A sky with no light at all (the sun far below the horizon, every texel in the
    // planet's shadow): lookups of it are 0 exactly, so the many-views radiance() skips them.
    dark_ = true;
    for (int j = 0; j < height && dark_; ++j)
        for (int i = 0; i < width; ++i)
            if (texture_.at(i, j) != Spectrum4(0.0f)) {
                dark_ = false;
                break;
            }
}

namespace {

// acos for the latitude mapping, without a branch, so that a loop of it vectorises:
// acos a = pi/2 - asin a for 0 <= a <= 1/2, 2 asin sqrt((1 - a) / 2) above, and
// acos(-a) = pi - acos a, with asin t = t + t z P(z) (z = t^2) on [0, 1/2] by the
// polynomial of Cephes' asinf (S. Moshier, Cephes Math Library), evaluated in double.
// Within 1e-8 rad of std::acos (measured 5.1e-9, at mu = 1/2; tests/cpp/
// test_skyview_lut.cpp): a millionth of a sky-view texel row.
WELKIN_ALWAYS_INLINE double zenith_angle_of(double mu) {
    const double a = mu < 0.0 ? -mu : mu;
    const bool big = a > 0.5;
    const double z = big ? 0.5 * (1.0 - a) : a * a;
    const double t = big ? std::sqrt(z) : a;
    const double p =
        ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z +
         1.6666752422e-1) *
            z * t +
        t;
    const double acos_a = big ? 2.0 * p : 0.5 * kPi - p;
    return mu < 0.0 ? kPi - acos_a : acos_a;
}

// Hillaire's latitude mapping (above), computed both ways and one selected. The exact
// horizon, theta = theta_h, is sky: a ray tangent to the ground does not hit it (mu = 0 from
// the ground; geometry.hpp's ray_hits_ground), as every other method sees it.
WELKIN_ALWAYS_INLINE float v_of_zenith_angle(double theta, double theta_h, double beta, int h) {
    // Above: s = 1 - sqrt(1 - theta / theta_h), row j = s / s_last (h/2 - 1) (upper_row_s).
    const double s = 1.0 - std::sqrt(max_value(1.0 - theta / theta_h, 0.0));
    const double rows_per_s = double(h / 2 - 1) / (1.0 - 1.0 / double(h)), inv_h = 1.0 / double(h);
    const double row = min_value(s * rows_per_s, double(h / 2 - 1));
    const float above = float((row + 0.5) * inv_h);  // stays above the horizon
    const float below = max_value(float(0.5 * (1.0 + std::sqrt(max_value((theta - theta_h) / beta, 0.0)))),
                                  (float(h / 2) + 0.5f) / float(h));  // stay below it
    return theta <= theta_h ? above : below;
}

// (u, v) as the texel coordinates of a bilinear lookup, as Texture2D::sample takes them:
// the left texel i and weight fx in u, the lower row j and weight fy in v. A NaN (from a
// zero or non-finite direction, which callers reject) selects texel 0 rather than an
// index out of the texture.
WELKIN_ALWAYS_INLINE void texel_of(float u, float v, int width, int height, int& i, float& fx, int& j,
                                   float& fy) {
    const float ux = u * float(width) - 0.5f, vy = v * float(height) - 0.5f;
    const float tx = ux > 0.0f ? min_value(ux, float(width - 1)) : 0.0f;
    const float ty = vy > 0.0f ? min_value(vy, float(height - 1)) : 0.0f;
    i = min_value(int(tx), width - 2);
    j = min_value(int(ty), height - 2);
    fx = tx - float(i);
    fy = ty - float(j);
}

Float4 fetch(const Texture2D& t, int i, float fx, int j, float fy) {
    const Spectrum4* const lo = &t.at(0, j);
    return Texture2D::Row{lo, lo + t.width(), fy, t.width() - 1}.sample4(i, fx);
}

}  // namespace

double SkyViewLut::zenith_angle(double mu) { return zenith_angle_of(mu); }

Spectrum4 SkyViewLut::radiance(double mu, double cos_phi) const {
    // The stored texel centres sit at u = (i + 0.5) / width exactly, so sample without the
    // texcoord_from_unit remapping.
    const float u = float(safe_sqrt(0.5 * (1.0 - clamp_cosine(cos_phi))));
    const float v = v_of_zenith_angle(zenith_angle_of(clamp_cosine(mu)), theta_h_, beta_, texture_.height());
    int i, j;
    float fx, fy;
    texel_of(u, v, texture_.width(), texture_.height(), i, fx, j, fy);
    return to_vec4(fetch(texture_, i, fx, j, fy));
}

namespace {

// The arithmetic pass of a block of lookups: from each view, mu and u =
// sqrt((1 - cos_phi) / 2) as view_geometry() and radiance(mu, cos_phi) compute them, then
// the texel coordinates (texel_of) of u and v = v_of_zenith_angle(zenith_angle_of(mu)).
WELKIN_SIMD_CLONES_WIDE void lookup_coordinates(const glm::dvec3* __restrict d, std::size_t n, double sx,
                                                double sy, double hs2, double theta_h, double beta, int width,
                                                int height, int* __restrict i_out, float* __restrict fx_out,
                                                int* __restrict j_out, float* __restrict fy_out) {
    for (std::size_t k = 0; k < n; ++k) {
        const double inv = 1.0 / std::sqrt(d[k].x * d[k].x + d[k].y * d[k].y + d[k].z * d[k].z);
        const double x = d[k].x * inv, y = d[k].y * inv;
        const double mu = clamp_value(d[k].z * inv, -1.0, 1.0);
        const double hv2 = x * x + y * y;
        const double c = clamp_value((x * sx + y * sy) / std::sqrt(max_value(hv2 * hs2, 1e-300)), -1.0, 1.0);
        const double cos_phi = (hv2 > 1e-24 && hs2 > 1e-24) ? c : 1.0;
        const float u = float(std::sqrt(max_value(0.5 * (1.0 - cos_phi), 0.0)));
        const float v = v_of_zenith_angle(zenith_angle_of(mu), theta_h, beta, height);
        texel_of(u, v, width, height, i_out[k], fx_out[k], j_out[k], fy_out[k]);
    }
}

}  // namespace

void SkyViewLut::radiance(std::span<const glm::dvec3> directions, const glm::dvec3& sun, std::size_t count,
                          float* out, std::size_t stride) const {
    if (dark_) {  // every texel is 0, so is every bilinear lookup (finite weights)
        for (std::size_t k = 0; k < directions.size(); ++k) std::fill_n(out + k * stride, count, 0.0f);
        return;
    }
    const double hs2 = sun.x * sun.x + sun.y * sun.y;
    constexpr std::size_t kBlock = 64;
    int i_tex[kBlock], j_tex[kBlock];
    float fx[kBlock], fy[kBlock];
    const int width = texture_.width(), height = texture_.height();
    for (std::size_t first = 0; first < directions.size(); first += kBlock) {
        const std::size_t n = std::min(kBlock, directions.size() - first);
        lookup_coordinates(directions.data() + first, n, sun.x, sun.y, hs2, theta_h_, beta_, width, height,
                           i_tex, fx, j_tex, fy);
        for (std::size_t k = 0; k < n; ++k) {
            const Float4 L = fetch(texture_, i_tex[k], fx[k], j_tex[k], fy[k]);
            float* const o = out + (first + k) * stride;
            for (std::size_t c = 0; c < count; ++c) o[c] = L[c];
        }
    }
}

}  // namespace welkin
