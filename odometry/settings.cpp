// SPDX-License-Identifier: BSD-3-Clause
#include "odometry/settings.hpp"

#include <string>

#include "common/errors.hpp"

namespace lidarcal::odometry {

void OdometrySettings::validate() const {
  const auto bad = [](const char* name, const std::string& problem) {
    throw InputError("", name, problem);
  };
  if (trimming_rounds < 0) bad("trimming_rounds", "must not be negative");
  if (!(trim_percentile > 50.0 && trim_percentile <= 100.0))
    bad("trim_percentile", "must lie in (50, 100] percent");
  if (min_samples < 3) bad("min_samples", "must be at least 3 (the closed form's least)");
  if (!(min_wheel_spread >= 0.0 && min_wheel_spread < 1.0))
    bad("min_wheel_spread", "must lie in [0, 1)");
  if (!(min_translation_spread >= 0.0 && min_translation_spread < 1.0))
    bad("min_translation_spread", "must lie in [0, 1)");
}

}  // namespace lidarcal::odometry
