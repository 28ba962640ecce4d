// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/span_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <utility>

#include "calibration/inversion.hpp"
#include "common/information_criteria.hpp"
#include "common/number_text.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

/// One order fitted to all entries and to all but each group of them.
struct OrderResult {
  SpanModelFit fit;
  bool cross_validated = false;  ///< every leave-one-group-out fit was determined
  double cv_mse_m2 = kNaN;       ///< mean squared error of the entries left out with their group
  /// per entry, fitted without its group (NaN where not determined)
  std::vector<double> left_out_error_m;
  bool invertible = false;                      ///< f increases over the fitted distances
  std::pair<double, double> range{kNaN, kNaN};  ///< true distances the fit gives the readings
};

/// The true distances of the readings under f: the walls' beams at the distances their fits
/// give, and the tapes' known ones.
std::pair<double, double> fittedDistances(const SpanProblem& p, const BiasPolynomial& f) {
  double lo = 1e300, hi = -1e300;
  for (const SpanWall& w : p.walls) {
    const WallDistance wd = wallDistance(w, f);
    if (!wd.ok) continue;
    for (const auto& b : w.beams) {
      const double d = wd.distance_m / std::max(std::cos(b.angle_rad - wd.normal_rad), 0.05);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  for (const TapeEntry& t : p.tapes)
    for (double d : t.d_m) lo = std::min(lo, d), hi = std::max(hi, d);
  return {lo, hi};
}

OrderResult evaluateOrder(const SpanProblem& p, int order) {
  OrderResult r;
  const std::size_t n = p.entries();
  const std::vector<bool> all(n, true);
  r.fit = fitSpanModel(p, order, all);
  if (!r.fit.identifiable) return r;
  const BiasPolynomial f{r.fit.alpha};
  r.range = fittedDistances(p, f);
  r.invertible = r.range.first <= r.range.second && isMonotone(f, r.range.first, r.range.second);
  r.left_out_error_m.assign(n, kNaN);
  const std::vector<std::size_t> group = p.groups();
  const std::size_t groups = *std::max_element(group.begin(), group.end()) + 1;
  if (groups < 2) return r;
  r.cross_validated = true;
  double sum = 0.0;
  for (std::size_t g = 0; g < groups; ++g) {
    std::vector<bool> use(n);
    for (std::size_t k = 0; k < n; ++k) use[k] = group[k] != g;
    const SpanModelFit without = fitSpanModel(p, order, use);
    if (!without.identifiable) {
      r.cross_validated = false;
      continue;
    }
    for (std::size_t k = 0; k < n; ++k)
      if (!use[k]) {
        r.left_out_error_m[k] = without.error_m(static_cast<Eigen::Index>(k));
        sum += r.left_out_error_m[k] * r.left_out_error_m[k];
      }
  }
  if (r.cross_validated) r.cv_mse_m2 = sum / static_cast<double>(n);
  return r;
}

/// Known-distance readings of the walls under f: every reading, in every scan, of the beams
/// the wall's fit used, at the distance the fit gives it. Walls are numbered from first_entry.
std::vector<KnownReading> wallReadings(const LandmarkObservations& obs, const SpanProblem& p,
                                       const BiasPolynomial& f, std::size_t first_entry) {
  std::vector<KnownReading> out;
  for (std::size_t w = 0; w < p.walls.size(); ++w) {
    const SpanWall& wall = p.walls[w];
    const WallDistance wd = wallDistance(wall, f);
    if (!wd.ok) continue;
    std::set<long long> used;
    for (const auto& b : wall.beams)
      used.insert(beamKey(BeamReading{b.angle_rad, b.reading_m, b.beam}));
    for (const WallSighting& ws : obs.walls) {
      if (ws.stop != wall.stop || ws.wall != wall.wall) continue;
      for (const BeamReading& b : ws.beams) {
        if (!std::isfinite(b.range_m) || !used.count(beamKey(b))) continue;
        const double d = wd.distance_m / std::max(std::cos(b.angle_rad - wd.normal_rad), 0.05);
        out.push_back({first_entry + w, ws.stop, ws.scan, b.beam, d, b.range_m, b.angle_rad});
      }
    }
  }
  return out;
}

/// The order-selection table: one row per order the entries determine.
std::vector<OrderRow> orderTable(const std::vector<OrderResult>& results, std::size_t entries) {
  std::vector<OrderRow> rows;
  for (const OrderResult& r : results) {
    if (!r.fit.identifiable) continue;
    OrderRow row;
    row.order = r.fit.order;
    row.alpha = r.fit.alpha;
    const double k = r.fit.order == 0 ? 1.0 : r.fit.order + 1.0;
    // chi2 is -2 log L up to a constant the orders share
    row.aic = akaike(k, 0.5 * r.fit.chi2);
    row.bic = schwarz(k, entries, 0.5 * r.fit.chi2);
    row.validation_mse_m2 = r.cv_mse_m2;
    row.test_mse_m2 = kNaN;
    row.invertible = r.invertible;
    rows.push_back(row);
  }
  return rows;
}

/// sigma_e of sigma = sigma_e f(d)^k from the readings' residuals.
double noiseScale(const std::vector<KnownReading>& readings, const BiasPolynomial& f,
                  double exponent) {
  double s = 0.0;
  for (const KnownReading& r : readings) {
    const double w =
        exponent == 0.0 ? 1.0 : std::pow(std::max(std::abs(f(r.d_m)), 1e-3), -2.0 * exponent);
    s += w * std::pow(r.y_m - f(r.d_m), 2);
  }
  return readings.empty() ? 0.0 : std::sqrt(s / static_cast<double>(readings.size()));
}

/// Each entry uncorrected, under the chosen fit, and left out with its group.
std::vector<SpanCheck> entryChecks(const SpanProblem& problem, const OrderResult& chosen) {
  std::vector<SpanCheck> checks;
  const Eigen::VectorXd raw = entryErrors(problem, BiasPolynomial{});
  const std::size_t spans = problem.spans.size();
  for (std::size_t k = 0; k < problem.entries(); ++k) {
    SpanCheck c;
    c.entry = problem.name(k);
    c.stop = k < spans ? problem.spans[k].stop : problem.tapes[k - spans].stop;
    c.reference_m = k < spans ? problem.spans[k].distance_m : problem.tapes[k - spans].reference_m;
    c.raw_error_m = raw.size() ? raw(static_cast<Eigen::Index>(k)) : kNaN;
    c.fitted_error_m = chosen.fit.error_m(static_cast<Eigen::Index>(k));
    c.left_out_error_m = chosen.left_out_error_m.empty() ? kNaN : chosen.left_out_error_m[k];
    checks.push_back(c);
  }
  return checks;
}

/// The order with the smallest cross-validated error among those identifiable and invertible
/// (with one pair of walls, nothing to cross-validate with: the offset); -1: none.
int chooseOrder(const std::vector<OrderResult>& results, bool one_group) {
  int best = -1;
  for (const OrderResult& r : results) {
    const bool candidate =
        r.fit.identifiable && r.invertible && (one_group ? r.fit.order == 0 : r.cross_validated);
    if (candidate && (best < 0 || r.cv_mse_m2 < results[static_cast<std::size_t>(best)].cv_mse_m2))
      best = r.fit.order;
  }
  return best;
}

/// What the spans cannot say: an offset only, no spare entry, or entries that disagree.
void addSpanWarnings(const std::vector<OrderResult>& results, const OrderResult& chosen,
                     std::vector<std::string>& warnings) {
  if (results.size() > 1 && !results[1].fit.identifiable)
    warnings.push_back(
        "the measured entries determine an offset only (f(d) = d + alpha_0): spans between one "
        "pair of "
        "walls, or pairs of one length, fix the sum of two distances and nothing else; measure "
        "spans "
        "between walls at other distances (the room's other axis, a cabinet in front of a wall) or "
        "tape "
        "distances to determine a scale");
  if (chosen.fit.dof == 0)
    warnings.push_back(
        "no spare measured entry: the standard errors rest on sigma_m alone and hold nothing the "
        "model "
        "misses (measure one more span to check them)");
  else if (chosen.fit.chi2 > static_cast<double>(chosen.fit.dof))
    warnings.push_back(
        "the measured entries disagree with the model by " +
        fixed(std::sqrt(chosen.fit.chi2 / static_cast<double>(chosen.fit.dof)), 1) +
        " times what their sigma_m says; the standard errors are widened by that factor");
}

}  // namespace

CalibrationModel calibrateWithSpans(const LandmarkObservations& obs, const SpanProblem& problem,
                                    const std::vector<KnownReading>& tape,
                                    const CalibrationConfig& config, std::vector<SpanCheck>* checks,
                                    std::vector<KnownReading>* fitted_readings) {
  config.validate();
  CalibrationModel m;
  m.method = "reference";
  m.model.range_min_m = obs.range_min_m;
  m.model.range_max_m = obs.range_max_m;
  const std::size_t n = problem.entries();
  if (n == 0) {
    m.status.code = StatusCode::too_few_reference_stops;
    m.status.message = "no span and no distance was found in the data";
    return m;
  }
  std::vector<OrderResult> results;
  for (int order = 0; order <= config.max_order; ++order)
    results.push_back(evaluateOrder(problem, order));
  const std::vector<std::size_t> group = problem.groups();
  const bool one_group = *std::max_element(group.begin(), group.end()) == 0;
  const int best = chooseOrder(results, one_group);
  m.orders = orderTable(results, n);
  if (best < 0) {
    m.status.code = StatusCode::no_invertible_order;
    m.status.message =
        "no bias model the spans determine increases over the distances the walls stand at: "
        "measure "
        "spans between other walls, or tape distances";
    return m;
  }
  double best_aic = 1e300;
  for (const auto& row : m.orders)
    if (row.invertible && row.aic < best_aic) best_aic = row.aic, m.order_aic = row.order;
  const OrderResult& chosen = results[static_cast<std::size_t>(best)];
  const BiasPolynomial f{chosen.fit.alpha};
  m.order_rule =
      one_group
          ? "offset: one pair of walls measured (nothing to cross-validate with)"
          : "leave-one-out cross-validation over the pairs of walls spanned and the distances";
  m.order_validation = best;
  m.model.bias = f;
  const Eigen::MatrixXd& cov = chosen.fit.covariance;
  m.alpha_covariance.assign(cov.data(), cov.data() + cov.size());
  m.fitted_range_m = chosen.range;
  m.discrepancy.note =
      "not estimated for wall-to-wall spans: the standard errors are widened by the spans' "
      "disagreement with the model "
      "beyond their sigma_m (sqrt(chi^2 / dof)), which is as far as a few spans can see the "
      "sensor's departure from it";

  std::size_t first_wall_entry = 0;
  for (const TapeEntry& t : problem.tapes)
    first_wall_entry = std::max(first_wall_entry, t.entry + 1);
  std::vector<KnownReading> readings = wallReadings(obs, problem, f, first_wall_entry);
  readings.insert(readings.end(), tape.begin(), tape.end());
  const double exponent = testReadingNoise(readings, config, m.noise_fits);
  if (fitted_readings) *fitted_readings = readings;
  setNoiseLaw(m.model.noise, exponent, noiseScale(readings, f, exponent));
  m.readings = readings.size();
  double s = 0.0;
  for (const KnownReading& r : readings) s += std::pow(r.y_m - f(r.d_m), 2);
  m.residual_rms_m = readings.empty() ? 0.0 : std::sqrt(s / static_cast<double>(readings.size()));

  addSpanWarnings(results, chosen, m.warnings);
  if (checks) *checks = entryChecks(problem, chosen);
  return m;
}

}  // namespace lidarcal::calibration
