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

Spectrum4 SkyViewLut::radiance(double mu, double cos_phi) const {
    const int h = texture_.height();
    const double theta = std::acos(clamp_cosine(mu));
    const float u = float(safe_sqrt(0.5 * (1.0 - clamp_cosine(cos_phi))));
    float v;
    if (theta < theta_h_) {
        v = float(0.5 * (1.0 - safe_sqrt(1.0 - theta / theta_h_)));
        v = std::min(v, (float(h / 2) - 0.5f) / float(h));  // stay above the horizon
    } else {
        v = float(0.5 * (1.0 + safe_sqrt((theta - theta_h_) / beta_)));
        v = std::max(v, (float(h / 2) + 0.5f) / float(h));  // stay below it
    }
    // The stored texel centres sit at u = (i + 0.5) / width exactly, so sample without the
    // texcoord_from_unit remapping.
    return texture_.sample(u, v);
}

}  // namespace welkin
