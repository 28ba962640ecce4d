// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/calibration_config.hpp"

#include <stdexcept>

namespace lidarcal::calibration {

const char* toString(Method m) { return m == Method::closed_form ? "closed-form" : "joint"; }

const char* toString(JointOrderRule r) {
  switch (r) {
    case JointOrderRule::aic:
      return "aic";
    case JointOrderRule::aic_parsimonious:
      return "aic-parsimonious";
    case JointOrderRule::bic:
      return "bic";
  }
  return "unknown";
}

void CalibrationConfig::validate() const {
  if (max_order < 1 || max_order > 6)
    throw std::invalid_argument("CalibrationConfig: max_order must be 1..6");
  if (threads < 0)
    throw std::invalid_argument("CalibrationConfig: threads must be >= 0 (0: automatic)");
  triangulation.validate();
  JointConfig j = joint;
  j.order = 1;
  j.noise = noise;
  j.validate();
}

}  // namespace lidarcal::calibration
