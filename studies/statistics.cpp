#include "studies/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lidarcal::studies {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
  for (const auto& x : e) v += std::pow(x.radial_m - s.mean_radial_m, 2) + std::pow(x.tangential_m - s.mean_tangential_m, 2);
  s.variance_m2 = e.size() > 1 ? v / (n - 1.0) : kNaN;
  s.rmse_m = std::sqrt(s2 / n);
  s.error_m = quartiles(std::move(len));
  s.radial_m = quartiles(std::move(rad));
  return s;
}

}  // namespace

Quartiles quartiles(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  if (values.empty()) return Quartiles{kNaN, kNaN, kNaN};
  std::sort(values.begin(), values.end());
  return Quartiles{quantile(values, 0.25), quantile(values, 0.5), quantile(values, 0.75)};
}

const char* toString(PositionEstimator e) { return e == PositionEstimator::triangulation ? "triangulation" : "joint"; }

CellSummary summarize(const Cell& cell, const std::vector<TrialResult>& trials, int max_order) {
  CellSummary s;
  s.cell = cell;
  s.trials = trials.size();
  for (std::size_t k = 0; k < kEstimators; ++k) {
    RatioSummary& r = s.ratio[k];
    r.order_counts.assign(static_cast<std::size_t>(max_order) + 1, 0);
    std::vector<double> ratio, single;
    for (const TrialResult& t : trials) {
      const EstimatorOutcome& o = t.estimators[k];
      if (!o.ran) continue;
      ++r.runs;
      if (!o.ok) {
        ++r.failures;
        continue;
      }
      ratio.push_back(o.mse_ratio);
      single.push_back(o.mse_ratio_single);
      if (o.order >= 0 && o.order <= max_order) ++r.order_counts[static_cast<std::size_t>(o.order)];
    }
    r.mse_ratio = quartiles(std::move(ratio));
    r.mse_ratio_single = quartiles(std::move(single));
  }
  const std::array<Estimator, kPositionEstimators> source = {Estimator::closed_form, Estimator::joint};
  for (std::size_t p = 0; p < kPositionEstimators; ++p) {
    std::vector<PositionError> errors;
    std::size_t missing = 0;
    for (const TrialResult& t : trials) {
      const EstimatorOutcome& o = t.estimators[static_cast<std::size_t>(source[p])];
      if (!o.ran) continue;
      for (const auto& e : o.landmarks) {
        if (std::isfinite(e.radial_m) && std::isfinite(e.tangential_m)) errors.push_back(e);
        else ++missing;
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
