// SPDX-License-Identifier: BSD-3-Clause
#include "io/import.hpp"

#include <cstdio>
#include <cstdlib>

#include "common/errors.hpp"

namespace lidarcal::io {

void checkRangeLimits(double range_min_m, double range_max_m) {
  if (!(range_min_m >= 0.0) || range_min_m == std::numeric_limits<double>::infinity())
    throw InputError("", "--range-min", "must be a finite number >= 0",
                     "give the smallest valid reading in metres");
  if (!(range_max_m > range_min_m))
    throw InputError(
        "", "--range-max",
        "must be larger than the lower range limit (" + std::to_string(range_min_m) + " m)",
        "give the largest valid reading in metres");
}

double float32Decimal(float value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.7g", static_cast<double>(value));
  return std::strtod(text, nullptr);
}

}  // namespace lidarcal::io
