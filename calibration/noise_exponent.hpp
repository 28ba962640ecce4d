// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Alhashimi et al. 2016 section 4: which power of f(d) scales the noise? Hypotheses (eq. 10)
//   H_k: y = f(d) + f(d)^k e,  k = 0..3,
// compared by their likelihood on batches of readings taken at a constant distance
// (repeated scans at one stop: the same beam sees the same spot), eqs. 13-15.

#include <array>
#include <vector>

namespace lidarcal::calibration {

struct NoiseExponentTest {
  std::array<double, 4> sigma_e2{};        ///< eq. 14 for k = 0..3
  std::array<double, 4> log_likelihood{};  ///< eq. 15 for k = 0..3 (with constants)
  int best = -1;                           ///< k with the largest likelihood; -1 when not testable
  std::size_t batches = 0;                 ///< batches used (at least `min_batch` readings each)
  std::size_t readings = 0;                ///< readings used
};

/// Runs the test. Each batch holds the readings of one constant distance in acquisition order.
NoiseExponentTest testNoiseExponent(const std::vector<std::vector<double>>& batches,
                                    std::size_t min_batch = 3);

}  // namespace lidarcal::calibration
