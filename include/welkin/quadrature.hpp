// Gauss-Legendre rules shared by the exact integrators.
#pragma once

#include <array>

namespace welkin {

// 8-point Gauss-Legendre on [-1, 1] (Abramowitz & Stegun, table 25.4): the positive nodes
// and their weights; the rule is symmetric, so node -x_i has weight w_i too.
inline constexpr std::array<double, 4> kGauss8Nodes = {0.1834346424956498, 0.5255324099163290,
                                                       0.7966664774136267, 0.9602898564975363};
inline constexpr std::array<double, 4> kGauss8Weights = {0.3626837833783620, 0.3137066458778873,
                                                         0.2223810344533745, 0.1012285362903763};

}  // namespace welkin
