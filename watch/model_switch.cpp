// SPDX-License-Identifier: BSD-3-Clause
#include "watch/model_switch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "calibration/calibrate.hpp"
#include "common/number_text.hpp"

namespace lidarcal::watch {

namespace {

/// Distances where two models are compared.
constexpr int kCompareDistances = 11;

/// Largest and mean squared curve standard error of `m` at the distances.
std::pair<double, double> curveErrors(const CalibrationModel& m, const std::vector<double>& d) {
  const Eigen::MatrixXd c = calibration::biasCovariance(m, d);
  if (c.size() == 0) return {HUGE_VAL, HUGE_VAL};
  double largest = 0.0, mean_sq = 0.0;
  for (Eigen::Index i = 0; i < c.rows(); ++i) {
    largest = std::max(largest, std::sqrt(std::max(0.0, c(i, i))));
    mean_sq += c(i, i) / static_cast<double>(c.rows());
  }
  return {largest, mean_sq};
}

std::string mm(double m) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f mm", 1000.0 * m);
  return text;
}

std::string pText(double p) {
  char text[32];
  std::snprintf(text, sizeof text, "p = %.2g", p);
  return text;
}

}  // namespace

std::vector<double> evenDistances(double lo, double hi, int count) {
  std::vector<double> d;
  for (int i = 0; i < count; ++i) d.push_back(lo + (hi - lo) * i / std::max(1, count - 1));
  return d;
}

SwitchDecision decideSwitch(const CalibrationModel& candidate, const CalibrationModel* in_use,
                            const SwitchTest& test, const LearnSettings& settings) {
  SwitchDecision s;
  if (in_use) s.test = test;
  s.plausible = candidate.status.ok() && candidate.plausibility.trustworthy();
  if (!candidate.status.ok() || !candidate.fitted_range_m) {
    s.reason = "no candidate: " + candidate.status.message;
    return s;
  }
  auto [lo, hi] = *candidate.fitted_range_m;
  if (in_use && in_use->fitted_range_m) {
    lo = std::max(lo, in_use->fitted_range_m->first);
    hi = std::min(hi, in_use->fitted_range_m->second);
  }
  if (!(hi > lo)) {
    s.reason = "the candidate was fitted at distances the model in use never saw";
    return s;
  }
  const std::vector<double> d = evenDistances(lo, hi, kCompareDistances);
  const auto [largest, mean_sq] = curveErrors(candidate, d);
  s.largest_se_m = largest;
  s.determined = largest <= settings.max_standard_error_m;
  if (in_use) {
    s.difference = calibration::compareModels(candidate, *in_use, d);
    s.differs = test.tested && test.f.p < settings.switch_level;
    double diff_sq = 0.0;
    for (double x : s.difference.difference_m)
      diff_sq += x * x / static_cast<double>(s.difference.difference_m.size());
    s.determined = s.determined && 2.0 * mean_sq < diff_sq;
  }
  s.adopt = s.determined && s.plausible && (!in_use || s.differs);
  if (s.adopt)
    s.reason = in_use ? "the sensor differs from the model in use (" + pText(test.f.p) +
                            "), it is determined to " + mm(largest) + " and plausible"
                      : "the candidate is determined to " + mm(largest) + " and plausible";
  else if (!s.plausible)
    s.reason = "the candidate fails calibrate's plausibility checks";
  else if (in_use && !s.differs)
    s.reason = test.tested
                   ? "the sensor does not differ from the model in use (" + pText(test.f.p) +
                         ", level " + significant(settings.switch_level, 2) + ")"
                   : "not tested: " + test.why_not;
  else
    s.reason = "the candidate is determined to only " + mm(largest) + " (needs " +
               mm(settings.max_standard_error_m) +
               (in_use ? " and an expected error below the model in use's)" : ")");
  return s;
}

CalibrationModel refitModel(const LandmarkObservations& raw, const LearnSettings& settings,
                            int threads) {
  calibration::CalibrationConfig c;
  c.method = calibration::Method::joint;
  c.max_order = settings.max_order;
  c.threads = threads;
  c.joint.dense_covariance_max_parameters = 0;  // a pose per scan: the sparse QR (model_check.cpp)
  return calibration::calibrate(raw, c);
}

}  // namespace lidarcal::watch
