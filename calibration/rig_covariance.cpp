// SPDX-License-Identifier: BSD-3-Clause
// RigProblem's summary: the covariance of every free parameter (the inverse of J^T J over the
// whitened residuals and priors, the gauge held), the leverage of each pooled beam (its row of
// the hat matrix J (J^T J)^-1 J^T) and the estimates with their standard errors.

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "calibration/rig_problem.hpp"

namespace lidarcal::calibration::rig {
namespace {

/// The CRS Jacobian Ceres evaluates, as an Eigen sparse matrix.
Eigen::SparseMatrix<double, Eigen::RowMajor> toSparse(const ceres::CRSMatrix& j) {
  Eigen::SparseMatrix<double, Eigen::RowMajor> m(j.num_rows, j.num_cols);
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(j.values.size());
  for (int r = 0; r < j.num_rows; ++r)
    for (int k = j.rows[static_cast<std::size_t>(r)]; k < j.rows[static_cast<std::size_t>(r) + 1];
         ++k)
      t.emplace_back(r, j.cols[static_cast<std::size_t>(k)], j.values[static_cast<std::size_t>(k)]);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

}  // namespace

bool RigProblem::computeCovariance() {
  ceres::Problem problem;
  std::vector<ceres::ResidualBlockId> data;
  addResiduals(problem, false, &data);
  addVehiclePriors(problem);
  holdGauge(problem);
  // The free blocks in the order of params_, and each free parameter's column.
  std::vector<double*> blocks;
  column_of_.assign(params_.size(), -1);
  int columns = 0;
  const auto consider = [&](std::size_t offset, std::size_t size, int held_index) {
    double* p = &params_[offset];
    if (!problem.HasParameterBlock(p) || problem.IsParameterBlockConstant(p)) return;
    blocks.push_back(p);
    for (std::size_t i = 0; i < size; ++i)
      if (static_cast<int>(i) != held_index) column_of_[offset + i] = columns++;
  };
  for (std::size_t k = 0; k < obs_.vehicle.size(); ++k) consider(3 * k, 3, -1);
  for (std::size_t s = 0; s < obs_.sensors.size(); ++s) consider(mount_offset_ + 3 * s, 3, -1);
  for (std::size_t i = 0; i < pole_ids_.size(); ++i) consider(pole_offset_ + 2 * i, 2, -1);
  consider(radius_offset_, 1, -1);
  for (std::size_t s = 0; s < obs_.sensors.size(); ++s)
    consider(alpha_offset_[s], static_cast<std::size_t>(setup_.orders[s]) + 1,
             setup_.scale_held && s == config_.reference ? 1 : -1);

  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = blocks;
  options.apply_loss_function = false;
  ceres::CRSMatrix jacobian;
  problem.Evaluate(options, nullptr, nullptr, nullptr, &jacobian);
  const auto j = toSparse(jacobian);
  if (j.cols() == 0 || j.rows() < static_cast<Eigen::Index>(used_.size())) {
    out_.status = Status{StatusCode::too_few_readings, "no parameter is left to fit"};
    return false;
  }
  // J^T J scaled to a unit diagonal (Jacobi), so that readings far more precise than the priors
  // do not hide a direction the data leave free behind the scales' spread.
  Eigen::MatrixXd info = Eigen::MatrixXd(Eigen::SparseMatrix<double>(j.transpose() * j));
  const Eigen::VectorXd scale = info.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  info = scale.asDiagonal() * info * scale.asDiagonal();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(info);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-10)) {
    // Name the parameter the data leave free: the largest component of the weakest direction.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(info);
    Eigen::Index at = 0;
    eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&at);
    std::string what = "a parameter";
    for (std::size_t p = 0; p < column_of_.size(); ++p) {
      if (column_of_[p] != at) continue;
      if (p < mount_offset_)
        what = "the vehicle's pose at stop " + std::to_string(p / 3);
      else if (p < pole_offset_)
        what = "the mounting of " + obs_.sensors[(p - mount_offset_) / 3].name;
      else if (p < radius_offset_)
        what = "the position of pole " + std::to_string(pole_ids_[(p - pole_offset_) / 2]);
      else if (p == radius_offset_)
        what = "the pole radius";
      else
        what = "the range model of a sensor";
    }
    out_.status = Status{StatusCode::not_identifiable, "the data leave " + what + " undetermined"};
    return false;
  }
  covariance_ = scale.asDiagonal() *
                ldlt.solve(Eigen::MatrixXd::Identity(info.rows(), info.cols())) *
                scale.asDiagonal();
  // Leverage of each pooled beam: j_i C j_i^T over its row's few nonzeros.
  for (std::size_t r = 0; r < used_.size() && r < static_cast<std::size_t>(j.rows()); ++r) {
    double h = 0.0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator a(
             j, static_cast<Eigen::Index>(r));
         a; ++a)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator b(
               j, static_cast<Eigen::Index>(r));
           b; ++b)
        h += a.value() * covariance_(a.col(), b.col()) * b.value();
    leverage_[r] = h;
  }
  return true;
}

Eigen::MatrixXd RigProblem::covarianceBlock(std::size_t offset, std::size_t size) const {
  Eigen::MatrixXd c =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(size), static_cast<Eigen::Index>(size));
  for (std::size_t a = 0; a < size; ++a)
    for (std::size_t b = 0; b < size; ++b) {
      const int ca = column_of_[offset + a], cb = column_of_[offset + b];
      if (ca >= 0 && cb >= 0)
        c(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = covariance_(ca, cb);
    }
  return c;
}

/// Each sensor's mounting, range model and residuals; returns the log-likelihood of its beams
/// summed over the sensors and the number of beams in `samples_used`.
double RigProblem::summariseSensors(std::size_t* samples_used) {
  const auto samples = noiseSamples();
  const std::size_t S = obs_.sensors.size();
  out_.sensors.assign(S, RigSensorEstimate{});
  double ll = 0.0;
  *samples_used = 0;
  for (std::size_t s = 0; s < S; ++s) {
    RigSensorEstimate& e = out_.sensors[s];
    const double* m = mount(s);
    e.mounting = obs_.sensors[s].prior;
    e.mounting.x_m = m[0], e.mounting.y_m = m[1], e.mounting.yaw_rad = wrapAngle(m[2]);
    e.mounting.upside_down = setup_.flips[s] < 0.0;
    e.mounting_covariance = covarianceBlock(mount_offset_ + 3 * s, 3);
    e.mounting_held = setup_.frame == RigFrame::relative && s == config_.reference;
    e.model.bias.alpha.assign(alpha(s), alpha(s) + setup_.orders[s] + 1);
    e.model.noise = noise_[s].law;
    e.model.range_min_m = obs_.sensors[s].range_min_m;
    e.model.range_max_m = obs_.sensors[s].range_max_m;
    e.alpha_covariance =
        covarianceBlock(alpha_offset_[s], static_cast<std::size_t>(setup_.orders[s]) + 1);
    e.scale_held = setup_.scale_held && s == config_.reference;
    e.beam_scatter_m = noise_[s].tau_m;
    e.readings = readings_per_sensor_[s];
    e.residuals = samples[s].size();
    double ss = 0.0;
    for (const auto& x : samples[s]) ss += x.residual * x.residual;
    e.residual_rms_m =
        samples[s].empty() ? 0.0 : std::sqrt(ss / static_cast<double>(samples[s].size()));
    ll += pooledLogLikelihood(samples[s], noise_[s]);
    *samples_used += samples[s].size();
  }
  for (std::size_t s = 0; s < S; ++s) out_.sensors[s].d_min_m = 1e9, out_.sensors[s].d_max_m = 0.0;
  for (const std::size_t i : used_) {
    const PooledBeam& b = beams_[i];
    const double d = distanceOf(b, nullptr);
    out_.sensors[b.sensor].d_min_m = std::min(out_.sensors[b.sensor].d_min_m, d);
    out_.sensors[b.sensor].d_max_m = std::max(out_.sensors[b.sensor].d_max_m, d);
  }
  return ll;
}

/// Each pole's position with its covariance and the sensors that see it; per sensor, how many
/// poles it sees and how many of them another sensor sees too.
void RigProblem::summarisePoles() {
  for (std::size_t i = 0; i < pole_ids_.size(); ++i) {
    RigPoleEstimate p;
    p.id = pole_ids_[i];
    p.x_m = pole(i)[0], p.y_m = pole(i)[1];
    p.covariance = covarianceBlock(pole_offset_ + 2 * i, 2);
    for (const RigSighting& s : obs_.sightings)
      if (s.pole == p.id &&
          std::find(p.sensors.begin(), p.sensors.end(), s.sensor) == p.sensors.end())
        p.sensors.push_back(s.sensor);
    std::sort(p.sensors.begin(), p.sensors.end());
    for (const std::size_t s : p.sensors) {
      ++out_.sensors[s].poles;
      out_.sensors[s].shared_poles += p.sensors.size() > 1;
    }
    out_.poles.push_back(p);
  }
}

/// Every other sensor's mounting in the reference's frame, its covariance from both mountings'
/// joint covariance (their correlation is most of the relative mounting's precision).
void RigProblem::summariseRelativeMountings() {
  const std::size_t ref = config_.reference;
  for (std::size_t s = 0; s < obs_.sensors.size(); ++s) {
    if (s == ref) continue;
    Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
    const std::size_t offsets[2] = {mount_offset_ + 3 * ref, mount_offset_ + 3 * s};
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) {
        const int ca = column_of_[offsets[a / 3] + static_cast<std::size_t>(a % 3)];
        const int cb = column_of_[offsets[b / 3] + static_cast<std::size_t>(b % 3)];
        if (ca >= 0 && cb >= 0) c(a, b) = covariance_(ca, cb);
      }
    RigRelativeMounting r =
        relativeMountingWithCovariance(out_.sensors[ref].mounting, out_.sensors[s].mounting, c);
    r.reference = ref;
    r.sensor = s;
    out_.relative.push_back(r);
  }
}

void RigProblem::summarise() {
  std::size_t n_samples = 0;
  const double ll = summariseSensors(&n_samples);
  summarisePoles();
  for (std::size_t k = 0; k < obs_.vehicle.size(); ++k)
    out_.vehicle.push_back(Pose2{vehicle(k)[0], vehicle(k)[1], vehicle(k)[2]});
  out_.radius_m = *radius();
  out_.radius_se_m = std::sqrt(std::max(0.0, covarianceBlock(radius_offset_, 1)(0, 0)));
  summariseRelativeMountings();
  out_.parameters = static_cast<std::size_t>(covariance_.rows());
  out_.neg_log_likelihood = -ll;
  out_.bic = static_cast<double>(out_.parameters) *
                 std::log(std::max<double>(1.0, static_cast<double>(n_samples))) -
             2.0 * ll;
  out_.status = Status{StatusCode::ok, ""};
}

}  // namespace lidarcal::calibration::rig
