// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/joint_problem.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/stats_util.hpp"

namespace lidarcal::calibration::joint {

JointProblem::JointProblem(const LandmarkObservations& obs, const JointInit& init,
                           const JointConfig& config)
    : obs_(obs), init_(init), config_(config), fx_(config.effects) {
  config.validate();
  if (init.poses.size() != obs.commanded.size())
    throw std::invalid_argument("refineJoint: one initial pose per stop");
  out_.motion_prior = config.motion == MotionPrior::on ||
                      (config.motion == MotionPrior::automatic && continuousMotion(obs, config));
  motion_ = out_.motion_prior && init.poses.size() >= 2;
  initialiseModel();
  initialiseParameters();
  startEffectTerms();
  initialiseReadingWindow();
  initialiseDriftReference();
  initialiseReferenceIntensity();
  // Repeated scans from one pose: the readings of one beam on one landmark at one stop share
  // their geometry, so (Gaussian) sum_i (y_i - f)^2 = n (ybar - f)^2 + sum_i (y_i - ybar)^2, and
  // one residual sqrt(n) (ybar - f) / sigma carries all they say about the parameters: the cost
  // of a solve no longer grows with the scans per stop. Not when a term depends on the scan
  // (drift) or on each reading (mixed-pixel weights, a Student t's weights). The robust loss acts
  // on the group. With the dark-surface term a group also shares its intensity.
  pool_ = config.pool_repeated_scans && !fx_.drift && !fx_.mixed_pixels && !fx_.student_noise;
}

void JointProblem::initialiseModel() {
  out_.model = init_.model;
  out_.model.bias.alpha.resize(static_cast<std::size_t>(config_.order) + 1, 0.0);
  out_.model.noise.kind = config_.noise;
  if (config_.noise == NoiseKind::polynomial && out_.model.noise.beta.empty())
    out_.model.noise.beta.assign(static_cast<std::size_t>(config_.noise_order) + 1, 0.0);
  if (config_.noise == NoiseKind::power && init_.model.noise.kind != NoiseKind::power)
    out_.model.noise.exponent = 2.0;
  if (fx_.noise_exponent && out_.model.noise.kind == NoiseKind::squared) {
    out_.model.noise.kind = NoiseKind::power;
    // Held, the start's exponent is the law; fitted, the first solve weighs by the squared law.
    const bool held = config_.hold_noise_shape && init_.model.noise.kind == NoiseKind::power;
    out_.model.noise.exponent = held ? init_.model.noise.exponent : 2.0;
  }
}

void JointProblem::initialiseParameters() {
  const std::vector<double>& alpha = out_.model.bias.alpha;
  const std::size_t n_poses = init_.poses.size(), n_landmarks = init_.centres.size();
  params_.assign(3 * n_poses + 3 * n_landmarks + alpha.size() + 5, 0.0);
  double* next = params_.data();
  auto take = [&next](std::size_t n) {
    double* block = next;
    next += n;
    return block;
  };
  for (std::size_t k = 0; k < n_poses; ++k) {
    // A measured pose replaces the start and is held there (fixInactiveTerms).
    const auto known = config_.known_poses.find(k);
    const Pose2& p = known != config_.known_poses.end() ? known->second : init_.poses[k];
    poses_.push_back(take(3));
    poses_.back()[0] = p.x_m;
    poses_.back()[1] = p.y_m;
    poses_.back()[2] = p.yaw_rad;
  }
  for (const auto& [id, start] : init_.centres) {
    const auto known = config_.known_centres.find(id);
    const Eigen::Vector2d& c = known != config_.known_centres.end() ? known->second : start;
    double* block = centres_[id] = take(2);
    block[0] = c.x();
    block[1] = c.y();
  }
  n_alpha_ = alpha.size();
  alpha_ = take(n_alpha_);
  std::copy(alpha.begin(), alpha.end(), alpha_);
  for (const auto& [id, c] : init_.centres) offsets_[id] = take(1);
  radius_ = take(1);
  *radius_ = init_.radius_m;
  globals_ = take(3);
  scale_ = take(1);
  mixed_fraction_ = fx_.mixed_pixels ? 0.05 : 0.0;
  dof_ = fx_.student_noise ? 10.0 : 0.0;
}

/// The terms that are on start from the given estimates.
void JointProblem::startEffectTerms() {
  const JointEffectEstimates& e0 = init_.effects;
  if (fx_.landmark_offsets && !offsets_.empty() && !e0.landmark_offset_m.empty()) {
    // Internally the first landmark is the reference: its reported offset moves into alpha_0.
    auto first = e0.landmark_offset_m.find(offsets_.begin()->first);
    const double ref = first != e0.landmark_offset_m.end() ? first->second : 0.0;
    for (auto& [id, o] : offsets_) {
      auto it = e0.landmark_offset_m.find(id);
      *o = (it != e0.landmark_offset_m.end() ? it->second : 0.0) - ref;
    }
    alpha_[0] += ref;
  }
  if (fx_.drift) globals_[0] = e0.drift_m_per_scan;
  if (fx_.angle_offset) globals_[1] = e0.angle_offset_rad;
  if (fx_.incidence_bias) globals_[2] = e0.incidence_bias_m;
  if (fx_.odometry_scale) *scale_ = e0.odometry_scale;
  if (fx_.incidence_noise) gamma_ = e0.incidence_noise_exponent;
  if (fx_.dark_noise) delta_ = e0.dark_noise_exponent;
  if (fx_.mixed_pixels && e0.mixed_pixel_fraction > 0.0) mixed_fraction_ = e0.mixed_pixel_fraction;
  if (fx_.student_noise && e0.student_dof > 2.0) dof_ = e0.student_dof;
}

/// The window of the outlier floor and the mixed pixels: the sensor's, or 1.25 x the largest
/// reading.
void JointProblem::initialiseReadingWindow() {
  out_.window_min_m = obs_.range_min_m;
  out_.window_max_m = obs_.range_max_m;
  if (!(obs_.range_max_m < 1e8)) {
    double m = 0.0;
    for (const auto& s : obs_.sightings)
      for (const auto& b : s.beams)
        if (std::isfinite(b.range_m)) m = std::max(m, b.range_m);
    out_.window_max_m = 1.25 * std::max(m, 1e-3);
  }
  window_max_ = out_.window_max_m;
}

/// Drift reference: the mean scan index of the readings.
void JointProblem::initialiseDriftReference() {
  double sum = 0.0, n = 0.0;
  for (const auto& s : obs_.sightings) {
    sum += static_cast<double>(s.scan) * static_cast<double>(s.beams.size());
    n += static_cast<double>(s.beams.size());
  }
  out_.effects.drift_reference_scan = n > 0 ? sum / n : 0.0;
  t_ref_ = out_.effects.drift_reference_scan;
}

/// I_ref of the dark-surface noise: the start's, else the median intensity of the readings (0:
/// none recorded; every reading's darkness is then 0).
void JointProblem::initialiseReferenceIntensity() {
  reference_intensity_ = init_.effects.dark_reference_intensity;
  if (reference_intensity_ > 0.0) return;
  std::vector<double> v;
  for (const auto& s : obs_.sightings)
    for (const auto& b : s.beams)
      if (std::isfinite(b.range_m) && b.hasIntensity()) v.push_back(b.intensity);
  reference_intensity_ = v.empty() ? 0.0 : median(v);
}

/// Readings on the central part of each landmark (lateral offset < fraction * radius): beams
/// near the edges have range derivatives that blow up at the tangent. Re-selected from the
/// current estimate before every solve (unless the caller selected them: keep_all_beams).
void JointProblem::selectReadings() {
  readings_.clear();
  for (const auto& s : obs_.sightings) {
    auto it = centres_.find(s.landmark);
    if (it == centres_.end() || s.stop >= poses_.size()) continue;
    const auto& p = poses_[s.stop];
    for (std::size_t j = 0; j < s.beams.size(); ++j) {
      const auto& b = s.beams[j];
      if (!std::isfinite(b.range_m)) continue;
      const bool edge = j == 0 || j + 1 == s.beams.size();
      if (config_.keep_all_beams) {
        readings_.push_back({s.stop, s.scan, s.landmark, b.angle_rad, b.range_m, edge,
                             darkness(b.intensity, reference_intensity_)});
        continue;
      }
      const double a = p[2] + b.angle_rad + globals_[1];
      const double perp =
          (it->second[1] - p[1]) * std::cos(a) - (it->second[0] - p[0]) * std::sin(a);
      if (std::abs(perp) < config_.lateral_fraction * *radius_)
        readings_.push_back({s.stop, s.scan, s.landmark, b.angle_rad, b.range_m, edge,
                             darkness(b.intensity, reference_intensity_)});
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Per reading at the current estimate

void JointProblem::updateGeometry() {
  geo_.resize(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    const auto& r = readings_[i];
    geo_[i] =
        beamGeometry(poses_[r.stop], r.angle_rad + globals_[1], centres_.at(r.landmark), *radius_);
  }
}

/// The terms that are off hold their neutral values (zero), so the full expression serves every
/// case.
double JointProblem::meanOf(std::size_t i, const BiasPolynomial& f) const {
  const auto& r = readings_[i];
  return expectedReading(f(geo_[i].d), *offsets_.at(r.landmark), globals_[0],
                         static_cast<double>(r.scan) - t_ref_, globals_[2], geo_[i].cos_inc);
}

double JointProblem::sigmaOf(std::size_t i, const RangeModel& m) const {
  return readingSigma(m.noise, m.bias,
                      {geo_[i].d, geo_[i].cos_inc, gamma_, readings_[i].darkness, delta_});
}

std::vector<double> JointProblem::residualsNow(const BiasPolynomial& f) const {
  std::vector<double> res(readings_.size());
  for (std::size_t i = 0; i < readings_.size(); ++i) res[i] = readings_[i].y_m - meanOf(i, f);
  return res;
}

/// Mixed pixels (EM): the responsibility of the uniform for each outermost beam; the fit weighs
/// a reading by 1 - responsibility. Student-t noise (EM for the t as a scale mixture of
/// Gaussians): a reading of residual r weighs (nu + 1) / (nu + (r / s)^2), s = sigma sqrt((nu - 2)
/// / nu) the t's scale; the residual is r / s, so the weight carries nu / (nu - 2) too.
void JointProblem::updateResponsibilities(const std::vector<double>& res) {
  weight_.assign(readings_.size(), 1.0);
  if (fx_.student_noise && dof_ > 2.0) {
    const double to_scale = dof_ / (dof_ - 2.0);
    for (std::size_t i = 0; i < readings_.size(); ++i) {
      const double u2 = res[i] * res[i] / (sigma_[i] * sigma_[i]) * to_scale;
      weight_[i] = (dof_ + 1.0) / (dof_ + u2) * to_scale;
    }
  }
  if (!fx_.mixed_pixels) return;
  for (std::size_t i = 0; i < readings_.size(); ++i) {
    if (!readings_[i].edge) continue;
    const double mean = readings_[i].y_m - res[i];
    const double u = (res[i] >= 0.0 && readings_[i].y_m <= window_max_ && window_max_ > mean)
                         ? 1.0 / (window_max_ - mean)
                         : 0.0;
    const double z = res[i] / sigma_[i];
    const double nd = std::exp(-0.5 * z * z) / (sigma_[i] * std::sqrt(2.0 * kPi));
    weight_[i] =
        1.0 - mixed_fraction_ * u / (mixed_fraction_ * u + (1.0 - mixed_fraction_) * nd + 1e-300);
  }
}
}  // namespace lidarcal::calibration::joint
