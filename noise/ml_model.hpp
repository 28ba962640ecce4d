// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Private to the ML noise estimator (ml.cpp, ml_adjustment.cpp): the model's residuals and
// Jacobians, shared by the Ceres costs and the redundancy computation, and the Ceres costs.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Core>

#include "noise/ml.hpp"

namespace lidarcal::noise::ml {

/// Linearised observation: residual (model - reading) and Jacobians of range (row 0) and
/// bearing (row 1) w.r.t. the pose (x, y, theta) and the landmark (x, y). The bias enters with
/// derivative 1 on its own component.
struct ObservationLinear {
  double res[2];
  double d_pose[2][3];
  double d_landmark[2][2];
};

inline void linearizeObservation(const Pose2& pose, const double* lm, const double* bias,
                                 const Observation& o, ObservationLinear& out) {
  const double dx = lm[0] - pose.x_m, dy = lm[1] - pose.y_m;
  const double q = std::max(dx * dx + dy * dy, 1e-18), rho = std::sqrt(q);
  out.res[0] = rho + bias[0] - o.range_m;
  out.res[1] = wrapAngle(std::atan2(dy, dx) - pose.yaw_rad + bias[1] - o.bearing_rad);
  out.d_pose[0][0] = -dx / rho, out.d_pose[0][1] = -dy / rho, out.d_pose[0][2] = 0.0;
  out.d_pose[1][0] = dy / q, out.d_pose[1][1] = -dx / q, out.d_pose[1][2] = -1.0;
  out.d_landmark[0][0] = dx / rho, out.d_landmark[0][1] = dy / rho;
  out.d_landmark[1][0] = -dy / q, out.d_landmark[1][1] = dx / q;
}

/// Linearised motion residual: relative pose of b in the frame of a, minus the command.
struct OdometryLinear {
  double res[3];
  double d_a[3][3];
  double d_b[3][3];
};

inline void linearizeOdometry(const Pose2& a, const Pose2& b, const OdometryStep& u,
                              OdometryLinear& out) {
  const double c = std::cos(a.yaw_rad), s = std::sin(a.yaw_rad);
  const double ddx = b.x_m - a.x_m, ddy = b.y_m - a.y_m;
  const double rx = c * ddx + s * ddy, ry = -s * ddx + c * ddy;
  out.res[0] = rx - u.dx_m;
  out.res[1] = ry - u.dy_m;
  out.res[2] = wrapAngle(b.yaw_rad - a.yaw_rad - u.dtheta_rad);
  const double da[3][3] = {{-c, -s, ry}, {s, -c, -rx}, {0.0, 0.0, -1.0}};
  const double db[3][3] = {{c, s, 0.0}, {-s, c, 0.0}, {0.0, 0.0, 1.0}};
  std::copy(&da[0][0], &da[0][0] + 9, &out.d_a[0][0]);
  std::copy(&db[0][0], &db[0][0] + 9, &out.d_b[0][0]);
}

inline Pose2 poseOf(const double* p) { return Pose2{p[0], p[1], p[2]}; }

inline std::vector<std::string> groupNames(int sensors) {
  std::vector<std::string> names;
  for (int s = 0; s < sensors; ++s) {
    names.push_back("s" + std::to_string(s) + ".range");
    names.push_back("s" + std::to_string(s) + ".bearing");
  }
  for (const char* n : {"process.dx", "process.dy", "process.dtheta"}) names.push_back(n);
  return names;
}

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

// Ceres cost functions: whitened by the current 1/sigma of their groups.

class ObservationCost final : public ceres::CostFunction {
 public:
  ObservationCost(const Observation& o, bool with_pose, const double* inv_sigma)
      : o_(o), with_pose_(with_pose), inv_sigma_(inv_sigma) {
    set_num_residuals(2);
    if (with_pose_) mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(2);
    mutable_parameter_block_sizes()->push_back(2);
  }
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const int l = with_pose_ ? 1 : 0;
    ObservationLinear lin;
    linearizeObservation(with_pose_ ? poseOf(p[0]) : Pose2{}, p[l], p[l + 1], o_, lin);
    const double w[2] = {inv_sigma_[0], inv_sigma_[1]};
    for (int c = 0; c < 2; ++c) r[c] = w[c] * lin.res[c];
    if (!J) return true;
    for (int c = 0; c < 2; ++c) {
      if (with_pose_ && J[0])
        for (int i = 0; i < 3; ++i) J[0][c * 3 + i] = w[c] * lin.d_pose[c][i];
      if (J[l])
        for (int i = 0; i < 2; ++i) J[l][c * 2 + i] = w[c] * lin.d_landmark[c][i];
      if (J[l + 1])
        for (int i = 0; i < 2; ++i) J[l + 1][c * 2 + i] = i == c ? w[c] : 0.0;
    }
    return true;
  }

 private:
  Observation o_;
  bool with_pose_;
  const double* inv_sigma_;  // range, bearing of this observation's sensor
};

class OdometryCost final : public ceres::CostFunction {
 public:
  OdometryCost(const OdometryStep& u, bool from_origin, const double* inv_sigma)
      : u_(u), from_origin_(from_origin), inv_sigma_(inv_sigma) {
    set_num_residuals(3);
    if (!from_origin_) mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* p, double* r, double** J) const override {
    const int b = from_origin_ ? 0 : 1;
    OdometryLinear lin;
    linearizeOdometry(from_origin_ ? Pose2{} : poseOf(p[0]), poseOf(p[b]), u_, lin);
    for (int c = 0; c < 3; ++c) r[c] = inv_sigma_[c] * lin.res[c];
    if (!J) return true;
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < 3; ++i) {
        if (!from_origin_ && J[0]) J[0][c * 3 + i] = inv_sigma_[c] * lin.d_a[c][i];
        if (J[b]) J[b][c * 3 + i] = inv_sigma_[c] * lin.d_b[c][i];
      }
    return true;
  }

 private:
  OdometryStep u_;
  bool from_origin_;
  const double* inv_sigma_;  // dx, dy, dtheta
};

/// What the adjustment's normal matrix tells at a state and variances (ml_adjustment.cpp).
struct AdjustmentAnalysis {
  std::vector<double> redundancy;  // per group: sum of the redundancy numbers r_ii
  // per group: sum of r_ii^2 (diagonal Fisher information of the variance)
  std::vector<double> redundancy_sq;
  double log_det_normal = 0.0;  // log det N (whitened normal matrix)
  // per sensor, range and bearing interleaved (NaN when not estimated)
  std::vector<double> bias_std;
  Eigen::MatrixXd fisher;  // with_information: G x G information of the variances (see below)
};

/// The normal matrix of the adjustment at `state` under `variances` (2S + 3, order of
/// MlNoiseResult::groups): redundancy per group, log det N, the biases' standard errors and,
/// `with_information`, the REML information of the variances.
AdjustmentAnalysis analyseAdjustment(const NoiseProblem& problem, const MlState& state,
                                     const std::vector<double>& variances, bool with_biases,
                                     bool with_information = false);

}  // namespace lidarcal::noise::ml
