// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/calibrate.hpp"

#include <string>

#include "calibration/joint_stage.hpp"
#include "calibration/noise_fits.hpp"

namespace lidarcal::calibration {
namespace {

/// Stage 1 into the model: one landmark per triangulated one; returns how many are usable.
int addTriangulated(CalibrationModel& m, const std::vector<LandmarkEstimate>& tri, double radius) {
  int usable = 0;
  for (const auto& l : tri) {
    CalibratedLandmark c;
    c.id = l.id;
    c.x_m = l.x_m;
    c.y_m = l.y_m;
    c.radius_m = radius;
    c.covariance_m2 = {l.covariance(0, 0), l.covariance(0, 1), l.covariance(1, 0),
                       l.covariance(1, 1)};
    c.stops = l.stops;
    c.status = l.ok() ? "ok" : std::string(toString(l.status)) + ": " + l.message;
    m.landmarks.push_back(c);
    usable += l.ok();
  }
  return usable;
}

}  // namespace

CalibrationModel calibrate(const LandmarkObservations& obs, const CalibrationConfig& config) {
  config.validate();
  CalibrationModel m;
  m.method = toString(config.method);
  m.model.range_min_m = obs.range_min_m;
  m.model.range_max_m = obs.range_max_m;
  if (refuseUnusableInput(m, obs, config)) return m;
  const double baseline = pathExtent(obs.commanded);

  // 1. Triangulate every landmark from its bearings at the commanded stops (Alhashimi et al. 2021,
  // 3.1).
  const auto tri = triangulateAll(obs, config.triangulation);
  const double radius = landmarkRadius(obs);
  const int usable = addTriangulated(m, tri, radius);
  if (refuseTriangulation(m, tri, usable, radius)) return m;

  // 2. Closed-form seed: landmark-stop distances, the order, the bias and the noise law (3.2).
  const auto pairs = closedFormPairs(obs, tri, radius, false);
  if (refuseTooFewPairs(m, obs, config, tri, pairs.size(), usable)) return m;
  const ClosedFormSeed seed = closedFormSeed(obs, tri, radius, pairs, config);
  fillClosedForm(m, obs, tri, seed, config);
  const auto batches = constantDistanceBatches(obs);
  if (config.method == Method::closed_form) {
    // 4. Side estimators on the closed form's pairs; its covariance by the jackknife over stops.
    fillNoiseFits(m, seed.order, seed.d_m, seed.y_m, batches, config.threads);
    m.alpha_covariance =
        closedFormCovariance(obs, config, radius, static_cast<int>(m.model.bias.alpha.size()) - 1);
    // 5. Plausibility.
    addPlausibilityWarnings(m, nullptr);
    return m;
  }

  // 3. Joint refinement (ours) from the closed form; a refusal keeps the closed form's side
  // estimators.
  const JointStage js = jointStage(obs, config, tri, seed, radius, m.model);
  if (refuseJoint(m, js.result, obs, usable, baseline)) {
    fillNoiseFits(m, seed.order, seed.d_m, seed.y_m, batches, config.threads);
    return m;
  }
  fillJoint(m, js, config);
  // 4. Side estimators on the joint refinement's readings and distances.
  fillNoiseFits(m, m.model.bias.order(), js.result.distances_m, js.result.readings_m, batches,
                config.threads);
  // 5. Plausibility.
  addPlausibilityWarnings(m, &js.result);
  return m;
}

}  // namespace lidarcal::calibration
