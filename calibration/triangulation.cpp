// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/triangulation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "common/plural.hpp"

namespace lidarcal::calibration {

void TriangulationConfig::validate() const {
  if (!(sigma_s_m > 0.0) || !(sigma_theta_rad > 0.0))
    throw std::invalid_argument(
        "TriangulationConfig: sigma_s_m and sigma_theta_rad must be positive");
  if (min_stops < 2)
    throw std::invalid_argument("TriangulationConfig: min_stops must be at least 2");
  if (!(max_condition > 1.0))
    throw std::invalid_argument("TriangulationConfig: max_condition must exceed 1");
}

const char* toString(TriangulationStatus s) {
  switch (s) {
    case TriangulationStatus::ok:
      return "ok";
    case TriangulationStatus::too_few_stops:
      return "too_few_stops";
    case TriangulationStatus::degenerate_geometry:
      return "degenerate_geometry";
    case TriangulationStatus::ill_conditioned:
      return "ill_conditioned";
  }
  return "unknown";
}

std::size_t centralBeam(const Sighting& s) {
  std::size_t best = 0;
  double best_gap = 1e300;
  for (std::size_t i = 0; i < s.beams.size(); ++i) {
    const double gap = std::abs(wrapAngle(s.beams[i].angle_rad - s.bearing_rad));
    if (gap < best_gap) {
      best_gap = gap;
      best = i;
    }
  }
  return best;
}

std::vector<int> landmarkIds(const LandmarkObservations& obs) {
  std::set<int> ids;
  for (const auto& s : obs.sightings) ids.insert(s.landmark);
  return {ids.begin(), ids.end()};
}

std::vector<StopBearing> stopBearings(const LandmarkObservations& obs, int landmark) {
  struct Acc {
    double sin = 0, cos = 0, sum = 0, sum2 = 0;
    int n = 0;
  };
  std::map<std::size_t, Acc> acc;
  for (const auto& s : obs.sightings) {
    if (s.landmark != landmark || s.beams.empty()) continue;
    Acc& a = acc[s.stop];
    a.sin += std::sin(s.bearing_rad);
    a.cos += std::cos(s.bearing_rad);
    const double r = s.beams[centralBeam(s)].range_m;
    a.sum += r;
    a.sum2 += r * r;
    ++a.n;
  }
  std::vector<StopBearing> out;
  out.reserve(acc.size());
  for (const auto& [stop, a] : acc) {
    if (stop >= obs.commanded.size())
      throw std::out_of_range("stopBearings: sighting refers to a stop without a pose");
    StopBearing b;
    b.stop = stop;
    b.bearing_world_rad = wrapAngle(obs.commanded[stop].yaw_rad + std::atan2(a.sin, a.cos));
    b.range_m = a.sum / a.n;
    b.range_var_m2 = a.n > 1 ? std::max(0.0, (a.sum2 - a.sum * a.sum / a.n) / (a.n - 1)) : 0.0;
    b.scans = a.n;
    out.push_back(b);
  }
  return out;
}

namespace {

/// Largest angle between two bearing lines (lines, so modulo pi).
double bearingSpread(const std::vector<StopBearing>& bearings) {
  double spread = 0.0;
  for (std::size_t i = 0; i < bearings.size(); ++i)
    for (std::size_t j = i + 1; j < bearings.size(); ++j) {
      double a = std::abs(wrapAngle(bearings[i].bearing_world_rad - bearings[j].bearing_world_rad));
      a = std::min(a, kPi - a);
      spread = std::max(spread, a);
    }
  return spread;
}

/// The weight of one bearing line (eq. 25 with repeated scans' range variance).
double lineWeight(const StopBearing& sb, bool have_var, const TriangulationConfig& config) {
  const double ss = config.sigma_s_m * config.sigma_s_m,
               st = config.sigma_theta_rad * config.sigma_theta_rad;
  double weight = 1.0;
  switch (config.weights) {
    case LineWeights::paper:
      weight = have_var ? 1.0 / ss + 1.0 / (st * sb.range_var_m2)  // eq. 25
                        : 1.0 / (ss + sb.range_m * sb.range_m * st);
      break;
    case LineWeights::residual:
      weight = 1.0 / (ss + sb.range_m * sb.range_m * st);
      break;
    case LineWeights::uniform:
      weight = 1.0;
      break;
  }
  return weight;
}

}  // namespace

LandmarkEstimate triangulate(int id, const std::vector<StopBearing>& bearings,
                             const std::vector<Pose2>& commanded,
                             const TriangulationConfig& config) {
  config.validate();
  LandmarkEstimate est;
  est.id = id;
  est.stops = static_cast<int>(bearings.size());
  if (est.stops < config.min_stops) {
    est.status = TriangulationStatus::too_few_stops;
    est.message = "seen from " + plural(bearings.size(), "stop") + ", at least " +
                  std::to_string(config.min_stops) +
                  " are needed: place the landmark where more stops can see it";
    return est;
  }
  est.bearing_spread_rad = bearingSpread(bearings);

  // Rows of eq. 19 with the commanded positions (eq. 22): H = [sin, -cos],
  // b = sin(theta) x_k - cos(theta) y_k. (Eq. 22 as printed has the opposite sign of b;
  // eq. 9 and eq. 19 fix it as written here.)
  const std::size_t n = bearings.size();
  Eigen::MatrixXd H(n, 2);
  Eigen::VectorXd b(n), w(n);
  // Paper weights need var(d~) from repeated scans; without them fall back to the residual form.
  bool have_var = true;
  for (const auto& sb : bearings) have_var = have_var && sb.scans > 1 && sb.range_var_m2 > 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& sb = bearings[i];
    const Pose2& p = commanded.at(sb.stop);
    const double s = std::sin(sb.bearing_world_rad), c = std::cos(sb.bearing_world_rad);
    H(static_cast<Eigen::Index>(i), 0) = s;
    H(static_cast<Eigen::Index>(i), 1) = -c;
    b(static_cast<Eigen::Index>(i)) = s * p.x_m - c * p.y_m;
    w(static_cast<Eigen::Index>(i)) = lineWeight(sb, have_var, config);
  }
  const Eigen::Matrix2d N = H.transpose() * w.asDiagonal() * H;
  const Eigen::Vector2d rhs = H.transpose() * w.asDiagonal() * b;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(N);
  const double lmin = eig.eigenvalues()(0), lmax = eig.eigenvalues()(1);
  est.condition = lmin > 0.0 ? lmax / lmin : std::numeric_limits<double>::infinity();
  if (est.bearing_spread_rad < config.min_bearing_spread_rad) {
    est.status = TriangulationStatus::degenerate_geometry;
    est.message = "bearing lines are nearly parallel (spread " +
                  std::to_string(est.bearing_spread_rad * 180.0 / kPi) +
                  " degrees): the landmark is almost on the path line or too far; move it sideways "
                  "of the path";
    return est;
  }
  if (!(est.condition < config.max_condition)) {
    est.status = TriangulationStatus::ill_conditioned;
    est.message = "normal matrix is ill-conditioned (condition " + std::to_string(est.condition) +
                  "): the stops do not constrain this landmark";
    return est;
  }
  const Eigen::Vector2d x = N.ldlt().solve(rhs);  // eq. 23
  est.x_m = x(0);
  est.y_m = x(1);
  const Eigen::VectorXd r = H * x - b;  // signed distances of the lines from the centre
  est.residual_rms_m = std::sqrt(r.squaredNorm() / static_cast<double>(n));
  // Weights are known only up to scale: scale the covariance by the weighted residual variance.
  const double s2 = n > 2 ? r.dot(w.asDiagonal() * r) / static_cast<double>(n - 2) : 0.0;
  est.covariance = N.inverse() * s2;
  return est;
}

std::vector<LandmarkEstimate> triangulateAll(const LandmarkObservations& obs,
                                             const TriangulationConfig& config) {
  std::vector<LandmarkEstimate> out;
  for (int id : landmarkIds(obs))
    out.push_back(triangulate(id, stopBearings(obs, id), obs.commanded, config));
  return out;
}

}  // namespace lidarcal::calibration
