// SPDX-License-Identifier: Apache-2.0
// Gauss-Legendre rules shared by the exact integrators.
#pragma once

#include <array>
#include <vector>

namespace welkin {

// 8-point Gauss-Legendre on [-1, 1] (Abramowitz & Stegun, table 25.4): the positive nodes
// and their weights; the rule is symmetric, so node -x_i has weight w_i too.
inline constexpr std::array<double, 4> kGauss8Nodes = {0.1834346424956498, 0.5255324099163290,
                                                       0.7966664774136267, 0.9602898564975363};
inline constexpr std::array<double, 4> kGauss8Weights = {0.3626837833783620, 0.3137066458778873,
                                                         0.2223810344533745, 0.1012285362903763};

// n-point Gauss-Legendre rule on (0, 1), for any n >= 1: nodes x (descending) and weights
// w, summing to 1. Nodes by Newton's method on P_n from Tricomi's initial guesses, weights
// 2 / ((1 - t^2) P_n'(t)^2) on [-1, 1], halved for the unit interval.
void gauss_legendre_unit(int n, std::vector<double>& x, std::vector<double>& w);

}  // namespace welkin
