// SPDX-License-Identifier: Apache-2.0
#include "welkin/base/quadrature.hpp"

#include <cmath>
#include <cstddef>

#include "welkin/base/math.hpp"

namespace welkin {

void gauss_legendre_unit(int n, std::vector<double>& x, std::vector<double>& w) {
    x.resize(std::size_t(n));
    w.resize(std::size_t(n));
    for (int i = 0; i < n; ++i) {
        double t = std::cos(kPi * (double(i) + 0.75) / (double(n) + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = t;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * t * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (t * p1 - p0) / (t * t - 1.0);
            const double dt = p1 / dp;
            t -= dt;
            if (std::abs(dt) < 1e-15) break;
        }
        x[std::size_t(i)] = 0.5 * (1.0 + t);
        w[std::size_t(i)] = 1.0 / ((1.0 - t * t) * dp * dp);
    }
}

}  // namespace welkin
