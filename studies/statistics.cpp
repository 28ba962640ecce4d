// SPDX-License-Identifier: BSD-3-Clause
#include "studies/statistics.hpp"
#include "common/stats_util.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lidarcal::studies {
namespace {

/// Type 7 quantile of sorted values.
double quantile(const std::vector<double>& sorted, double p) {
  const double h = (static_cast<double>(sorted.size()) - 1.0) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (h - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

PositionSummary positionSummary(const std::vector<PositionError>& e, std::size_t missing) {
  PositionSummary s;
  s.samples = e.size();
  s.missing = missing;
  if (e.empty()) {
    s.mean_radial_m = s.mean_tangential_m = s.bias_m = s.variance_m2 = s.rmse_m = kNaN;
    s.error_m = s.radial_m = Quartiles{kNaN, kNaN, kNaN};
    return s;
  }
  const double n = static_cast<double>(e.size());
  double sr = 0.0, st = 0.0, s2 = 0.0;
  std::vector<double> len, rad;
  for (const auto& x : e) {
    sr += x.radial_m;
    st += x.tangential_m;
    s2 += x.radial_m * x.radial_m + x.tangential_m * x.tangential_m;
    len.push_back(std::hypot(x.radial_m, x.tangential_m));
    rad.push_back(x.radial_m);
  }
  s.mean_radial_m = sr / n;
  s.mean_tangential_m = st / n;
  s.bias_m = std::hypot(s.mean_radial_m, s.mean_tangential_m);
  double v = 0.0;
  for (const auto& x : e)
    v += std::pow(x.radial_m - s.mean_radial_m, 2) +
         std::pow(x.tangential_m - s.mean_tangential_m, 2);
  s.variance_m2 = e.size() > 1 ? v / (n - 1.0) : kNaN;
  s.rmse_m = std::sqrt(s2 / n);
  s.error_m = quartiles(std::move(len));
  s.radial_m = quartiles(std::move(rad));
  return s;
}

}  // namespace

Quartiles quartiles(std::vector<double> values) { return sampleStats(std::move(values)).q; }

SampleStats sampleStats(std::vector<double> values) {
  values.erase(
      std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
      values.end());
  SampleStats s;
  s.n = values.size();
  if (values.empty()) {
    s.q = Quartiles{kNaN, kNaN, kNaN};
    s.mean = s.mean_se = s.median_se = kNaN;
    return s;
  }
  std::sort(values.begin(), values.end());
  s.q = Quartiles{quantile(values, 0.25), quantile(values, 0.5), quantile(values, 0.75)};
  const double n = static_cast<double>(values.size());
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / n;
  double ss = 0.0;
  for (double v : values) ss += (v - s.mean) * (v - s.mean);
  s.mean_se = values.size() > 1 ? std::sqrt(ss / (n - 1.0) / n) : kNaN;
  const double half = 0.5 / std::sqrt(n);  // the median's rank scatters by sqrt(n)/2 of n
  s.median_se = values.size() > 1
                    ? 0.5 * (quantile(values, 0.5 + half) - quantile(values, 0.5 - half))
                    : kNaN;
  return s;
}

const char* toString(PositionEstimator e) {
  return e == PositionEstimator::triangulation ? "triangulation" : "joint";
}

CellSummary summarize(const Cell& cell, const std::vector<TrialResult>& trials, int max_order) {
  CellSummary s;
  s.cell = cell;
  s.trials = trials.size();
  for (std::size_t k = 0; k < kEstimators; ++k) {
    RatioSummary& r = s.ratio[k];
    std::array<std::array<std::vector<double>, kTestSets>, kRules> values;
    for (auto& rule : r.rules) rule.order_counts.assign(static_cast<std::size_t>(max_order) + 1, 0);
    for (const TrialResult& t : trials) {
      const EstimatorOutcome& o = t.estimators[k];
      if (!o.ran) continue;
      ++r.runs;
      if (!o.ok) {
        ++r.failures;
        continue;
      }
      for (std::size_t rule = 0; rule < kRules; ++rule) {
        const RuleOutcome& x = o.rules[rule];
        for (std::size_t set = 0; set < kTestSets; ++set)
          values[rule][set].push_back(x.mse_ratio[set]);
        if (x.order >= 0 && x.order <= max_order)
          ++r.rules[rule].order_counts[static_cast<std::size_t>(x.order)];
      }
    }
    for (std::size_t rule = 0; rule < kRules; ++rule)
      for (std::size_t set = 0; set < kTestSets; ++set)
        r.rules[rule].ratio[set] = sampleStats(std::move(values[rule][set]));
  }
  for (std::size_t set = 0; set < kTestSets; ++set) {
    std::vector<double> v;
    for (const TrialResult& t : trials) v.push_back(t.ceiling[set]);
    s.ceiling[set] = sampleStats(std::move(v));
  }
  const std::array<Estimator, kPositionEstimators> source = {Estimator::closed_form,
                                                             Estimator::joint};
  for (std::size_t p = 0; p < kPositionEstimators; ++p) {
    std::vector<PositionError> errors;
    std::size_t missing = 0;
    for (const TrialResult& t : trials) {
      const EstimatorOutcome& o = t.estimators[static_cast<std::size_t>(source[p])];
      if (!o.ran) continue;
      for (const auto& e : o.landmarks) {
        if (std::isfinite(e.radial_m) && std::isfinite(e.tangential_m))
          errors.push_back(e);
        else
          ++missing;
      }
    }
    s.position[p] = positionSummary(errors, missing);
  }
  double detected = 0.0;
  for (const TrialResult& t : trials) detected += t.detected_landmarks;
  s.detected_landmarks = trials.empty() ? kNaN : detected / static_cast<double>(trials.size());
  return s;
}

}  // namespace lidarcal::studies
