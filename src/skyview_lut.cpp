#include "welkin/skyview_lut.hpp"

#include <cmath>

#include <tbb/parallel_for.h>

#include "welkin/inscattering.hpp"

namespace welkin {

SkyViewLut::SkyViewLut(const AtmosphereBatch& batch, const TransmittanceLut& tlut,
                       const MultiScatteringLut& mslut, double r, double mu_s, int width,
                       int height, int steps)
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
                const double c = 1.0 - 2.0 * v;
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
            inscatter_row(batch, mslut, ray, mu_s, nu, std::span<Spectrum4>(&texture_.at(0, j), std::size_t(width)),
                          scratch);
        }
    });
}

float SkyViewLut::v_of_theta(double theta) const {
    const int h = texture_.height();
    float v;
    if (theta < theta_h_) {
        v = float(0.5 * (1.0 - safe_sqrt(1.0 - theta / theta_h_)));
        v = std::min(v, (float(h / 2) - 0.5f) / float(h));  // stay above the horizon
    } else {
        v = float(0.5 * (1.0 + safe_sqrt((theta - theta_h_) / beta_)));
        v = std::max(v, (float(h / 2) + 0.5f) / float(h));  // stay below it
    }
    return v;
}

Spectrum4 SkyViewLut::radiance(double mu, double cos_phi) const {
    const double theta = std::acos(clamp_cosine(mu));
    const float u = float(safe_sqrt(0.5 * (1.0 - clamp_cosine(cos_phi))));
    // The stored texel centres sit at u = (i + 0.5) / width exactly, so sample without the
    // texcoord_from_unit remapping.
    return texture_.sample(u, v_of_theta(theta));
}

namespace {

// The arithmetic pass of a block of lookups: mu and u = sqrt((1 - cos_phi) / 2) of each
// view, as view_geometry() and radiance(mu, cos_phi) compute them.
void view_angles(const glm::dvec3* __restrict d, std::size_t n, double sx, double sy, double hs2,
                 double* __restrict mu, float* __restrict u) {
    for (std::size_t k = 0; k < n; ++k) {
        const double inv = 1.0 / std::sqrt(d[k].x * d[k].x + d[k].y * d[k].y + d[k].z * d[k].z);
        const double x = d[k].x * inv, y = d[k].y * inv;
        mu[k] = clamp_value(d[k].z * inv, -1.0, 1.0);
        const double hv2 = x * x + y * y;
        const double c = clamp_value((x * sx + y * sy) / std::sqrt(max_value(hv2 * hs2, 1e-300)), -1.0, 1.0);
        const double cos_phi = (hv2 > 1e-24 && hs2 > 1e-24) ? c : 1.0;
        u[k] = float(std::sqrt(max_value(0.5 * (1.0 - cos_phi), 0.0)));
    }
}

}  // namespace

void SkyViewLut::radiance(std::span<const glm::dvec3> directions, const glm::dvec3& sun, std::size_t count,
                          float* out, std::size_t stride) const {
    const double hs2 = sun.x * sun.x + sun.y * sun.y;
    constexpr std::size_t kBlock = 64;
    double mu[kBlock];
    float u[kBlock];
    const float width = float(texture_.width());
    for (std::size_t first = 0; first < directions.size(); first += kBlock) {
        const std::size_t n = std::min(kBlock, directions.size() - first);
        view_angles(directions.data() + first, n, sun.x, sun.y, hs2, mu, u);
        for (std::size_t k = 0; k < n; ++k) {
            const float v = v_of_theta(std::acos(mu[k]));
            const Float4 L = texture_.row(v).sample4(u[k] * width - 0.5f);
            float* const o = out + (first + k) * stride;
            for (std::size_t c = 0; c < count; ++c) o[c] = L[c];
        }
    }
}

}  // namespace welkin
