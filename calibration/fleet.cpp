// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/fleet.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>

#include "calibration/model_comparison.hpp"
#include "common/errors.hpp"
#include "common/multiple_testing.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

// 1 / Phi^-1(3/4): MAD to standard deviation for normal data
constexpr double kMadToSd = 1.482602218505602;
// variance of a median of n normal values: (pi / 2) sigma^2 / n
constexpr double kHalfPi = 1.5707963267948966;

/// Against the calibration before: the distances inside both fitted ranges.
FleetTest movedTest(const FleetEntry& now, const FleetEntry& before,
                    const std::vector<double>& distances_m) {
  const calibration::ModelDifference diff =
      calibration::compareModels(now.model, before.model, distances_m);
  FleetTest t;
  t.why_not = diff.why_not;
  t.difference_m = diff.difference_m;
  if (!diff.tested) return t;
  t.tested = true;
  t.distances_m = diff.distances_m;
  t.statistic = diff.wald.statistic;
  t.dof = diff.wald.dof;
  t.p = diff.wald.p;
  return t;
}

/// Robust summary of the other sensors' bias at one distance.
struct FleetAt {
  std::size_t n = 0;             ///< sensors
  double median_m = kNaN;        ///< their median bias
  double sd_m = kNaN;            ///< 1.4826 MAD
  double typical_var_m2 = kNaN;  ///< median of their own squared standard errors
};

FleetAt fleetAt(const std::vector<double>& bias, const std::vector<double>& var) {
  FleetAt f;
  f.n = bias.size();
  if (bias.empty()) return f;
  f.median_m = median(bias);
  std::vector<double> dev;
  for (double b : bias) dev.push_back(std::abs(b - f.median_m));
  f.sd_m = kMadToSd * median(dev);
  f.typical_var_m2 = median(var);
  return f;
}

/// Against the other sensors' current calibrations (`rows[self]` excluded), distance by distance.
FleetTest outlierTest(const std::vector<FleetRow>& rows, std::size_t self,
                      const FleetConfig& config) {
  FleetTest t;
  double smallest_p = 1.0;
  for (std::size_t j = 0; j < config.distances_m.size(); ++j) {
    const BiasAt& mine = rows[self].bias[j];
    if (!mine.inside || !std::isfinite(mine.se_m)) continue;
    std::vector<double> bias, var;
    for (std::size_t r = 0; r < rows.size(); ++r)
      if (r != self && rows[r].bias[j].inside && std::isfinite(rows[r].bias[j].se_m)) {
        bias.push_back(rows[r].bias[j].bias_m);
        var.push_back(rows[r].bias[j].se_m * rows[r].bias[j].se_m);
      }
    if (bias.size() < config.min_fleet) continue;
    const FleetAt f = fleetAt(bias, var);
    const double n = static_cast<double>(f.n);
    const double tau2 = std::max(0.0, f.sd_m * f.sd_m - f.typical_var_m2);
    const double scale = std::sqrt(tau2 + mine.se_m * mine.se_m + kHalfPi * f.sd_m * f.sd_m / n);
    const double z = (mine.bias_m - f.median_m) / scale;
    const int dof = static_cast<int>(f.n) - 1;
    const double p =
        2.0 * boost::math::cdf(boost::math::complement(boost::math::students_t(dof), std::abs(z)));
    t.distances_m.push_back(config.distances_m[j]);
    t.difference_m.push_back(mine.bias_m - f.median_m);
    t.z.push_back(z);
    t.statistic = std::max(t.statistic, std::abs(z));
    t.dof = t.dof == 0 ? dof : std::min(t.dof, dof);
    smallest_p = std::min(smallest_p, p);
  }
  if (t.distances_m.empty()) {
    t.why_not =
        "fewer than " + std::to_string(config.min_fleet) +
        " other sensors with standard errors at a distance inside this calibration's fitted range";
    return t;
  }
  t.tested = true;
  t.p = std::min(1.0, static_cast<double>(t.distances_m.size()) * smallest_p);
  return t;
}

/// Holm over the tested members of one family; sets p_holm and flagged.
void holm(std::vector<FleetTest*> family, double alpha) {
  std::vector<double> p;
  for (const FleetTest* t : family) p.push_back(t->tested ? t->p : kNaN);
  const std::vector<double> adjusted = holmAdjust(p);
  for (std::size_t i = 0; i < family.size(); ++i) {
    family[i]->p_holm = family[i]->tested ? adjusted[i] : 1.0;
    family[i]->flagged = family[i]->tested && adjusted[i] < alpha;
  }
}

/// The calibrations of each sensor, oldest first; refuses ambiguous histories.
std::map<std::string, std::vector<const FleetEntry*>> bySensor(
    const std::vector<FleetEntry>& entries) {
  std::map<std::string, std::vector<const FleetEntry*>> out;
  for (const FleetEntry& e : entries) out[e.sensor].push_back(&e);
  for (auto& [sensor, list] : out) {
    std::stable_sort(list.begin(), list.end(),
                     [](const FleetEntry* a, const FleetEntry* b) { return a->date < b->date; });
    for (std::size_t i = 1; i < list.size(); ++i) {
      if (list[i - 1]->date.empty() || list[i]->date == list[i - 1]->date)
        throw InputError(
            list[i]->source, "date",
            "sensor '" + sensor + "' has two calibrations " +
                (list[i - 1]->date.empty() ? "and one without a date" : "dated " + list[i]->date) +
                " (also " + list[i - 1]->source + ")",
            "give each calibration of a sensor its own date (a manifest: sensor,date,model)");
    }
  }
  return out;
}

}  // namespace

void FleetConfig::validate() const {
  if (distances_m.empty()) throw std::invalid_argument("FleetConfig: at least one distance");
  for (std::size_t i = 0; i < distances_m.size(); ++i)
    if (!(distances_m[i] > 0.0) || (i > 0 && !(distances_m[i] > distances_m[i - 1])))
      throw std::invalid_argument("FleetConfig: distances must be positive and increasing");
  if (!(alpha > 0.0 && alpha < 1.0))
    throw std::invalid_argument("FleetConfig: alpha must lie in (0, 1)");
  if (min_fleet < 2) throw std::invalid_argument("FleetConfig: min_fleet must be at least 2");
}

std::vector<BiasAt> biasAt(const CalibrationModel& m, const std::vector<double>& distances_m) {
  const Eigen::MatrixXd C = calibration::biasCovariance(m, distances_m);
  std::vector<BiasAt> out;
  for (std::size_t i = 0; i < distances_m.size(); ++i) {
    BiasAt b;
    b.distance_m = distances_m[i];
    b.bias_m = m.model.bias(b.distance_m) - b.distance_m;
    const Eigen::Index k = static_cast<Eigen::Index>(i);
    b.se_m = C.size() ? std::sqrt(std::max(0.0, C(k, k))) : kNaN;
    b.inside = calibration::insideFittedRange(m, b.distance_m);
    b.noise_m = m.model.noise.stddev(b.distance_m, m.model.bias);
    out.push_back(b);
  }
  return out;
}

FleetSummary summarizeFleet(const std::vector<FleetEntry>& entries, const FleetConfig& config) {
  config.validate();
  FleetSummary s;
  s.config = config;
  for (const auto& [sensor, list] : bySensor(entries)) {
    FleetRow row;
    row.current = *list.back();
    row.bias = biasAt(row.current.model, config.distances_m);
    if (list.size() > 1) {
      const FleetEntry& before = *list[list.size() - 2];
      row.previous = before;
      row.previous_bias = biasAt(before.model, config.distances_m);
      row.moved = movedTest(row.current, before, config.distances_m);
    } else {
      row.moved.why_not = "no previous calibration";
    }
    s.rows.push_back(std::move(row));
  }
  for (std::size_t i = 0; i < s.rows.size(); ++i)
    s.rows[i].outlier = outlierTest(s.rows, i, config);
  std::vector<FleetTest*> moved, outliers;
  for (FleetRow& r : s.rows) {
    moved.push_back(&r.moved);
    outliers.push_back(&r.outlier);
  }
  holm(moved, config.alpha);
  holm(outliers, config.alpha);
  for (std::size_t j = 0; j < config.distances_m.size(); ++j) {
    std::vector<double> bias, var;
    for (const FleetRow& r : s.rows)
      if (r.bias[j].inside) {
        bias.push_back(r.bias[j].bias_m);
        var.push_back(r.bias[j].se_m * r.bias[j].se_m);
      }
    const FleetAt f = fleetAt(bias, var);
    s.median_bias_m.push_back(f.median_m);
    s.robust_sd_m.push_back(f.sd_m);
    s.sensors_at.push_back(f.n);
  }
  for (const FleetRow& r : s.rows)
    if (r.moved.flagged || r.outlier.flagged) s.flagged.push_back(r.current.sensor);
  return s;
}

}  // namespace lidarcal::calibration
