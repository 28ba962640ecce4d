// SPDX-License-Identifier: BSD-3-Clause
#include "watch/model_check.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "calibration/calibrate.hpp"
#include "calibration/filtering.hpp"
#include "calibration/joint_refinement.hpp"
#include "calibration/model_comparison.hpp"
#include "common/ray_circle.hpp"
#include "common/rng.hpp"

namespace lidarcal::watch {

namespace {

calibration::CalibrationConfig lineFitConfig(const CheckFit& fit) {
  calibration::CalibrationConfig c;
  c.method = calibration::Method::joint;
  c.max_order = 1;  // g(d) = a_0 + a_1 d: an offset and a scale
  c.threads = fit.threads;
  // A stretch holds a pose per scan: the sparse QR gives the covariance in a fraction of the
  // time a dense SVD of the Jacobian takes (the pose priors make it full rank).
  c.joint.dense_covariance_max_parameters = 0;
  return c;
}

std::size_t countPoles(const LandmarkObservations& obs) {
  std::set<int> poles;
  for (const auto& s : obs.sightings) poles.insert(s.landmark);
  return poles.size();
}

}  // namespace

std::array<double, 2> referenceDistances(const CalibrationModel& m) {
  const auto [lo, hi] = m.fitted_range_m.value_or(
      std::make_pair(m.model.range_min_m, std::min(m.model.range_max_m, 1e3)));
  return {lo + 0.25 * (hi - lo), lo + 0.75 * (hi - lo)};
}

Eigen::Matrix2d modelShiftCovariance(const CalibrationModel& m, const std::array<double, 2>& d) {
  const std::vector<double> at(d.begin(), d.end());
  Eigen::MatrixXd c = calibration::biasCovariance(m, at);
  if (c.size() == 0) c = Eigen::MatrixXd::Zero(2, 2);
  for (Eigen::Index i = 0; i < 2; ++i) {
    if (m.discrepancy.estimated()) c(i, i) += m.discrepancy.sigma_m * m.discrepancy.sigma_m;
    for (Eigen::Index j = 0; j < 2; ++j)
      c(i, j) /= m.model.bias.derivative(d[static_cast<std::size_t>(i)]) *
                 m.model.bias.derivative(d[static_cast<std::size_t>(j)]);
  }
  return c;
}

LandmarkObservations correctedObservations(const LandmarkObservations& raw,
                                           const CalibrationModel& model) {
  const calibration::ReadingCorrector correct = calibration::readingCorrector(
      model, calibration::InversionMethod::ls, calibration::Outside::drop);
  LandmarkObservations out = raw;
  out.sightings.clear();
  for (const Sighting& s : raw.sightings) {
    Sighting c = s;
    c.beams.clear();
    for (const BeamReading& b : s.beams) {
      const calibration::CorrectedReading r = correct(b.range_m);
      if (r.fate != calibration::ReadingFate::corrected) continue;
      BeamReading cb = b;
      cb.range_m = r.range_m;
      c.beams.push_back(cb);
    }
    if (c.beams.empty()) continue;
    // The centre distance follows its surface reading: corrected as the nearest beam would be.
    const calibration::CorrectedReading near = correct(s.centre_range_m - s.radius_m);
    if (near.fate == calibration::ReadingFate::corrected)
      c.centre_range_m = near.range_m + s.radius_m;
    out.sightings.push_back(std::move(c));
  }
  return out;
}

LandmarkObservations replicaObservations(const LandmarkObservations& obs,
                                         const CalibrationModel& fit, std::uint64_t seed) {
  // Only poles the fit located: one it set aside (say, degenerate geometry) has no trustworthy
  // circle, and beams drawn from it can read below zero.
  const std::map<int, const CalibratedLandmark*> poles = locatedLandmarks(fit);
  std::mt19937_64 rng = makeRng(seed, 0);
  std::normal_distribution<double> normal(0.0, 1.0);
  LandmarkObservations out = obs;
  out.sightings.clear();
  for (const Sighting& s : obs.sightings) {
    const auto pole = poles.find(s.landmark);
    if (pole == poles.end() || s.stop >= fit.stop_poses.size()) continue;
    const Pose2& pose = fit.stop_poses[s.stop];
    const CalibratedLandmark& l = *pole->second;
    Sighting r = s;
    for (BeamReading& b : r.beams) {
      const double d = rayCircleDistance(pose.x_m, pose.y_m, pose.yaw_rad + b.angle_rad, l.x_m,
                                         l.y_m, l.radius_m);
      b.range_m = fit.model.bias(d) + fit.model.noise.stddev(d, fit.model.bias) * normal(rng);
    }
    double sx = 0.0, sy = 0.0;
    pose.toSensor(l.x_m, l.y_m, sx, sy);
    r.centre_range_m = std::hypot(sx, sy);
    r.bearing_rad = std::atan2(sy, sx);
    r.radius_m = l.radius_m;
    out.sightings.push_back(std::move(r));
  }
  return out;
}

namespace {

/// The bootstrap estimate of the line fit's bias at `d`: the replicas' mean shift minus the
/// fitted one; nullopt when no replica could be fitted.
std::optional<Eigen::Vector2d> fitBias(const LandmarkObservations& obs,
                                       const CalibrationModel& line, const std::vector<double>& d,
                                       const CheckFit& fit, int& used) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  used = 0;
  for (int k = 0; k < fit.bias_replicas; ++k) {
    const LandmarkObservations rep =
        replicaObservations(obs, line, deriveSeed(fit.seed, static_cast<std::uint64_t>(k)));
    const CalibrationModel m = calibration::calibrate(rep, lineFitConfig(fit));
    if (!m.status.ok()) continue;
    for (Eigen::Index i = 0; i < 2; ++i) {
      const double at = d[static_cast<std::size_t>(i)];
      sum(i) += m.model.bias(at) - line.model.bias(at);
    }
    ++used;
  }
  if (used == 0) return std::nullopt;
  return Eigen::Vector2d(sum / used);
}

}  // namespace

Shift fittedShift(const ModelCheck& check) {
  return {Eigen::Vector2d(check.shift_m[0], check.shift_m[1]), check.covariance};
}

Shift unbiasedShift(const ModelCheck& check) {
  if (check.bias_replicas <= 0) return fittedShift(check);
  return {Eigen::Vector2d(check.shift_m[0] - check.fit_bias_m[0],
                          check.shift_m[1] - check.fit_bias_m[1]),
          check.covariance * (1.0 + 1.0 / check.bias_replicas)};
}

ModelCheck checkModel(const LandmarkObservations& raw, const CalibrationModel& model,
                      const std::array<double, 2>& distances_m, const CheckFit& fit) {
  ModelCheck r;
  r.scans = raw.commanded.size();
  r.distance_m = distances_m;
  const LandmarkObservations obs = correctedObservations(raw, model);
  r.poles = countPoles(obs);
  for (const auto& s : obs.sightings) r.readings += s.beams.size();
  if (raw.sightings.empty()) {
    r.status = {StatusCode::no_usable_landmark, "no pole was seen in enough of the stretch's " +
                                                    std::to_string(r.scans) +
                                                    " scans to take part"};
    return r;
  }
  if (obs.sightings.empty()) {
    r.status = {StatusCode::too_few_observations,
                "no pole reading lies in the range the model was fitted over"};
    return r;
  }
  const CalibrationModel line = calibration::calibrate(obs, lineFitConfig(fit));
  if (!line.status.ok() || line.alpha_covariance.size() != 4 || !line.fitted_range_m) {
    r.status = line.status.ok() ? Status{StatusCode::joint_failed, "the fit has no covariance"}
                                : line.status;
    return r;
  }
  r.fitted_m = *line.fitted_range_m;
  r.readings = line.readings;
  const std::vector<double> d(distances_m.begin(), distances_m.end());
  Eigen::MatrixXd c = calibration::biasCovariance(line, d);
  // Parameters: a pose per scan, a centre per pole, the line, the noise scale, the radius when
  // estimated.
  const double n = static_cast<double>(line.readings);
  const double p = 3.0 * static_cast<double>(r.scans) + 2.0 * static_cast<double>(r.poles) + 3.0 +
                   (obs.landmark_radius_m ? 0.0 : 1.0);
  if (!(n > p + 2.0)) {
    r.status = {StatusCode::too_few_observations,
                "too few readings for the poses and poles of the stretch"};
    return r;
  }
  c *= n / (n - p);
  if (fit.bias_replicas > 0) {
    const std::optional<Eigen::Vector2d> b = fitBias(obs, line, d, fit, r.bias_replicas);
    if (!b) {
      r.status = {StatusCode::joint_failed,
                  "no replica of the stretch could be fitted, so the "
                  "check's own bias is unknown"};
      return r;
    }
    r.fit_bias_m = {(*b)(0), (*b)(1)};
  }
  for (std::size_t i = 0; i < 2; ++i) {
    r.shift_m[i] = line.model.bias(d[i]) - d[i];
    r.shift_se_m[i] = std::sqrt(c(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)));
  }
  r.covariance = c;
  if (!(r.covariance.determinant() > 0.0)) {
    r.status = {StatusCode::joint_failed, "the fit's covariance of the shift is singular"};
    return r;
  }
  r.status = {StatusCode::ok, ""};
  return r;
}

}  // namespace lidarcal::watch
