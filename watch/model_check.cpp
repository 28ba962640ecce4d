// SPDX-License-Identifier: BSD-3-Clause
#include "watch/model_check.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "calibration/calibrate.hpp"
#include "calibration/filtering.hpp"
#include "calibration/model_comparison.hpp"

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
