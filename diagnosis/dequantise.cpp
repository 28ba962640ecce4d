// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/dequantise.hpp"

#include <random>

#include "common/rng.hpp"

namespace lidarcal::diagnosis {

void dequantise(std::vector<double>& readings, double q, std::uint64_t seed) {
  auto gen = makeRng(seed, 0x0ULL);
  std::uniform_real_distribution<double> cell(-0.5 * q, 0.5 * q);
  for (double& y : readings) y += cell(gen);
}

}  // namespace lidarcal::diagnosis
