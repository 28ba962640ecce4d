// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The settings of calibrate() (calibrate.hpp): which method, the order rules, the noise law and
// the settings of each stage.

#include <cstddef>
#include <functional>

#include "calibration/joint_refinement.hpp"
#include "calibration/range_model_fit.hpp"
#include "calibration/triangulation.hpp"
#include "common/range_model.hpp"

namespace lidarcal::calibration {

enum class Method { closed_form, joint };
const char* toString(Method m);

/// How the joint refinement picks its order among 1..max_order.
enum class JointOrderRule {
  aic,               ///< smallest AIC
  aic_parsimonious,  ///< smallest order whose AIC is within 2 of the smallest (Burnham & Anderson)
  bic,               ///< smallest BIC
};
const char* toString(JointOrderRule r);

struct CalibrationConfig {
  Method method = Method::joint;                ///< closed form of the paper, or joint refinement
  int max_order = 4;                            ///< n_max of Alhashimi et al. 2021 phase 1
  OrderRule closed_form_rule = OrderRule::aic;  ///< order rule of the closed form
  /// order rule of the joint refinement
  JointOrderRule joint_rule = JointOrderRule::aic_parsimonious;
  NoiseKind noise = NoiseKind::squared;  ///< noise law of the calibrated model
  TriangulationConfig triangulation;     ///< stage 1 settings
  JointConfig joint;                     ///< stage 3 settings (order is chosen here)
  /// The stops must span at least this distance (metres) for the landmarks to be triangulated
  /// from bearings; below it calibrate() returns status no_baseline. Default 0.1 m.
  double min_baseline_m = 0.1;
  /// Progress of the joint refinement for a display (the library never prints): called with the
  /// stage name ("joint refinement"), the solves done and the solves in all (the settling pass,
  /// one per order, the covariance). Default empty: not called.
  std::function<void(const char* stage, std::size_t done, std::size_t total)> progress;
  /// Threads for the joint refinement's orders (independent solves from one settled geometry;
  /// the result does not depend on the number). 0: the machine's cores, at most 8. Default 0.
  int threads = 0;
  void validate() const;  ///< throws std::invalid_argument
};

}  // namespace lidarcal::calibration
