// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/refits.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "common/pose2.hpp"

namespace lidarcal::diagnosis::sequence {

JointConfig effectConfig(JointConfig c, Effect e) {
  if (!c.effects.enable(e))
    throw std::invalid_argument(std::string("diagnose: no joint term for the effect '") +
                                toString(e) + "'");
  return c;
}

JointConfig warmStartConfig(JointConfig c) {
  c.settle_geometry = false;
  c.outer_iterations = 2;
  c.max_solver_iterations = 200;
  return c;
}

double totalNegLogLikelihood(const JointResult& r) {
  return !r.ok() ? std::numeric_limits<double>::infinity()
                 : r.neg_log_likelihood + r.prior_neg_log_likelihood;
}

JointInit withOrder(JointInit i, int order) {
  i.model.bias.alpha.resize(static_cast<std::size_t>(order) + 1, 0.0);
  return i;
}

JointConfig baselineConfig(const CalibrationModel& cal, const CalibrationConfig& cc,
                           const LandmarkObservations& obs, const DiagnoseConfig& config) {
  JointConfig base;
  base.order = std::max(cal.model.bias.order(), 1);
  base.noise = NoiseKind::squared;
  base.sigma_s_m = cc.joint.sigma_s_m;
  base.sigma_psi_rad = deg2rad(2.0);  // prior of the heading_error model's per-stop headings
  base.estimate_radius = !obs.landmark_radius_m.has_value();
  base.keep_all_beams = true;
  base.reselect = false;
  base.covariance = false;
  base.outer_iterations = 4;
  base.outlier_floor = config.outlier_floor;
  // The published model holds each stop's heading at the commanded one (stop and go). A continuous
  // recording's odometry drifts in heading as in position, and its motion prior models both step by
  // step: there the baseline refines the headings (held at the drifting odometry, clean drives
  // would be named heading_error).
  base.effects.estimate_heading = continuousMotion(obs, base);
  base.cauchy_loss = true;
  return base;
}

}  // namespace lidarcal::diagnosis::sequence
