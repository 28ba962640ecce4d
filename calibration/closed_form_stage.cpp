// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/closed_form_stage.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include <Eigen/Dense>

#include "calibration/inversion.hpp"
#include "calibration/jackknife.hpp"
#include "calibration/noise_fits.hpp"
#include "common/information_criteria.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

/// Position of each scan within its stop (0, 1, 2, ...), from the sightings.
std::map<std::size_t, std::size_t> scanPositions(const LandmarkObservations& obs) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  std::map<std::size_t, std::size_t> pos;
  for (const auto& [stop, scans] : scans_of_stop) {
    std::size_t i = 0;
    for (std::size_t scan : scans) pos[scan] = i++;
  }
  return pos;
}

std::map<std::size_t, std::size_t> scansPerStop(const LandmarkObservations& obs) {
  std::map<std::size_t, std::set<std::size_t>> scans_of_stop;
  for (const auto& s : obs.sightings) scans_of_stop[s.stop].insert(s.scan);
  std::map<std::size_t, std::size_t> n;
  for (const auto& [stop, scans] : scans_of_stop) n[stop] = scans.size();
  return n;
}

/// RMS angle between the measured bearing lines and the triangulated centres (sigma_theta).
double bearingScatter(const LandmarkObservations& obs, const std::vector<LandmarkEstimate>& tri) {
  double s = 0.0;
  std::size_t n = 0;
  for (const auto& l : tri) {
    if (!l.ok()) continue;
    for (const auto& sb : stopBearings(obs, l.id)) {
      const Pose2& p = obs.commanded[sb.stop];
      const double predicted = std::atan2(l.y_m - p.y_m, l.x_m - p.x_m);
      s += std::pow(wrapAngle(sb.bearing_world_rad - predicted), 2);
      ++n;
    }
  }
  return n ? std::sqrt(s / static_cast<double>(n)) : 0.0;
}

}  // namespace

std::vector<RangePair> closedFormPairs(const LandmarkObservations& obs,
                                       const std::vector<LandmarkEstimate>& landmarks,
                                       double radius_m, bool per_scan) {
  std::map<int, const LandmarkEstimate*> ok;
  for (const auto& l : landmarks)
    if (l.ok()) ok[l.id] = &l;
  const auto position = scanPositions(obs);
  const auto per_stop = scansPerStop(obs);
  struct Acc {
    double d = 0, y = 0;
    int n = 0;
  };
  std::map<std::tuple<int, std::size_t, int>, Acc> groups;  // (landmark, stop, part)
  std::vector<RangePair> pairs;
  for (const auto& s : obs.sightings) {
    auto it = ok.find(s.landmark);
    if (it == ok.end() || s.beams.empty()) continue;
    const BeamReading& b = s.beams[centralBeam(s)];
    if (!std::isfinite(b.range_m)) continue;
    const Pose2& p = obs.commanded.at(s.stop);
    const double d = rayCircleDistance(p.x_m, p.y_m, p.yaw_rad + b.angle_rad, it->second->x_m,
                                       it->second->y_m, radius_m);
    // A beam that meets the triangulated circle behind the stop (or at it) cannot have read this
    // landmark: the triangulation placed it badly. Such a pair says nothing about f.
    if (!(d > 0.0) || !std::isfinite(d)) continue;
    // The paper's split (Alhashimi et al. 2021 section 4.3) into fit / choose / test thirds: by
    // scan within the stop when a stop has at least three scans, else by (landmark, stop).
    const int part = per_stop.at(s.stop) >= 3
                         ? static_cast<int>(position.at(s.scan) % 3)
                         : static_cast<int>((s.stop + static_cast<std::size_t>(s.landmark)) % 3);
    if (per_scan) {
      pairs.push_back({d, b.range_m, part});
    } else {
      Acc& a = groups[{s.landmark, s.stop, part}];
      a.d += d;
      a.y += b.range_m;
      ++a.n;
    }
  }
  for (const auto& [key, a] : groups) pairs.push_back({a.d / a.n, a.y / a.n, std::get<2>(key)});
  return pairs;
}

double landmarkRadius(const LandmarkObservations& obs) {
  if (obs.landmark_radius_m) return *obs.landmark_radius_m;
  std::vector<double> r;
  for (const auto& s : obs.sightings)
    if (s.radius_m > 0.0) r.push_back(s.radius_m);
  return median(r);
}

std::vector<std::vector<double>> constantDistanceBatches(const LandmarkObservations& obs) {
  std::map<std::tuple<std::size_t, int, std::uint32_t>, std::vector<std::pair<std::size_t, double>>>
      by_beam;
  for (const auto& s : obs.sightings)
    for (const auto& b : s.beams)
      if (std::isfinite(b.range_m) && b.beam != kUnknownBeam)
        by_beam[{s.stop, s.landmark, b.beam}].push_back({s.scan, b.range_m});
  std::vector<std::vector<double>> batches;
  for (auto& [key, v] : by_beam) {
    std::sort(v.begin(), v.end());
    std::vector<double> y;
    for (const auto& [scan, r] : v) y.push_back(r);
    batches.push_back(std::move(y));
  }
  return batches;
}

Admissible invertibleOver(double range_min_m, double range_max_m) {
  return [=](const std::vector<double>& alpha) {
    return alpha.size() >= 2 &&
           invertsReadingWindow(BiasPolynomial{alpha}, range_min_m, range_max_m);
  };
}

void fillOrders(CalibrationModel& m, const OrderSelection& sel, std::size_t n) {
  m.orders.clear();
  for (const auto& row : sel.table) {
    OrderRow o;
    o.invertible = row.admissible;
    o.order = row.order;
    o.alpha = row.alpha;
    o.aic = row.aic;
    const double k = row.order + 2.0;  // its free parameters, as the AIC counts them
    o.bic = schwarz(k, n, 0.5 * (row.aic - 2.0 * k));  // -log L read back from the AIC
    o.validation_mse_m2 = row.validation_mse_m2;
    o.test_mse_m2 = row.test_mse_m2;
    m.orders.push_back(o);
  }
  m.order_aic = sel.order_aic;
  m.order_validation = sel.order_validation;
  m.order_rule = toString(sel.rule);
}

double rmsResidual(const BiasPolynomial& f, const std::vector<double>& d,
                   const std::vector<double>& y) {
  double s = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) s += std::pow(y[i] - f(d[i]), 2);
  return d.empty() ? 0.0 : std::sqrt(s / static_cast<double>(d.size()));
}

ClosedFormSeed closedFormSeed(const LandmarkObservations& obs,
                              const std::vector<LandmarkEstimate>& tri, double radius_m,
                              const std::vector<RangePair>& pairs,
                              const CalibrationConfig& config) {
  ClosedFormSeed seed;
  seed.pairs = pairs.size();
  const bool window_known = obs.range_max_m < 1e8;
  seed.selection =
      selectOrder(pairs, config.max_order, config.closed_form_rule,
                  window_known ? invertibleOver(obs.range_min_m, obs.range_max_m) : Admissible{});
  seed.order = std::max(seed.selection.chosen, 1);
  for (const auto& p : closedFormPairs(obs, tri, radius_m, true)) {
    seed.d_m.push_back(p.d_m);
    seed.y_m.push_back(p.y_m);
  }
  return seed;
}

void fillClosedForm(CalibrationModel& m, const LandmarkObservations& obs,
                    const std::vector<LandmarkEstimate>& tri, const ClosedFormSeed& seed,
                    const CalibrationConfig& config) {
  const OrderSelection& sel = seed.selection;
  const std::vector<double>& d = seed.d_m;
  const std::vector<double>& y = seed.y_m;
  fillOrders(m, sel, seed.pairs);
  m.model.bias.alpha = sel.table[static_cast<std::size_t>(std::min<int>(
                                     seed.order, static_cast<int>(sel.table.size()) - 1))]
                           .alpha;
  m.model.noise = fitNoiseLaw(config.noise, seed.order, m.model.bias, d, y);
  m.residual_rms_m = rmsResidual(m.model.bias, d, y);
  m.readings = d.size();
  m.sigma_theta_rad = bearingScatter(obs, tri);
  m.stop_poses = obs.commanded;
  m.fitted_range_m = fittedRange(d, y, m.model.bias);
}

std::vector<double> closedFormCovariance(const LandmarkObservations& obs,
                                         const CalibrationConfig& config, double radius,
                                         int order) {
  std::vector<std::size_t> stops;
  for (const auto& s : obs.sightings) stops.push_back(s.stop);
  std::sort(stops.begin(), stops.end());
  stops.erase(std::unique(stops.begin(), stops.end()), stops.end());
  const std::size_t G = std::min(stops.size(), kClosedFormJackknifeGroups);
  if (G < 3) return {};
  std::map<std::size_t, std::size_t> group;  // stop -> group
  for (std::size_t k = 0; k < stops.size(); ++k) group[stops[k]] = k * G / stops.size();
  const std::size_t n = static_cast<std::size_t>(order) + 1;
  std::vector<Eigen::VectorXd> alphas;
  for (std::size_t g = 0; g < G; ++g) {
    LandmarkObservations without = obs;
    without.sightings.clear();
    for (const auto& s : obs.sightings)
      if (group[s.stop] != g) without.sightings.push_back(s);
    const auto pairs =
        closedFormPairs(without, triangulateAll(without, config.triangulation), radius, false);
    if (pairs.size() < n + 2) return {};
    const OrderSelection sel = selectOrder(pairs, order, config.closed_form_rule);
    const auto& a = sel.table[static_cast<std::size_t>(order)].alpha;
    if (a.size() != n) return {};
    alphas.push_back(Eigen::Map<const Eigen::VectorXd>(a.data(), static_cast<Eigen::Index>(n)));
  }
  const Eigen::MatrixXd cov = jackknifeCovariance(alphas);
  std::vector<double> out(n * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      out[i * n + j] = cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  return out;
}

}  // namespace lidarcal::calibration
