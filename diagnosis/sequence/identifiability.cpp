// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/identifiability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "common/pose2.hpp"
#include "diagnosis/sequence/pose_uncertainty.hpp"

namespace lidarcal::diagnosis::sequence {
namespace {

/// The linearised model for identifiability: the Jacobian in the nuisance parameters (bias,
/// radius when estimated, centres, stop positions with their priors, rows n.. for the priors),
/// the weights, and each mean-type effect's columns. Sparse where it grows with the data: a reading
/// touches the bias, the radius, one centre and one pose, and a long log has a pose per scan.
struct Design {
  using Sparse = Eigen::SparseMatrix<double>;
  Sparse j;
  Eigen::VectorXd w;
  Sparse x_lm, x_head;
  Eigen::MatrixXd x_drift, x_angle, x_inc, x_scale;
  std::size_t landmarks = 0;
  double tmin = 0.0, tmax = 0.0;  ///< scan range of the readings
};

/// The entries of a design's sparse blocks while its rows are written, and each stop's pose
/// slot (-1 for a stop without readings: its pose, free under its prior, takes up its prior's
/// rows whatever the effect, so it and they are left out; a continuous log has many such).
struct DesignEntries {
  std::vector<Eigen::Triplet<double>> j, lm, head;
  std::vector<int> slot;
  std::vector<std::size_t> stop_of_slot;  ///< the stop of each slot, in order
  int stride = 2;  ///< columns per pose: x, y, and under the motion prior the heading too
  int pose0 = 0;   ///< the first pose's column
};

/// Landmark id -> column of its centre's x (y at +1), from column `col` on.
std::map<int, int> centreColumns(const JointResult& fit, int col) {
  std::map<int, int> lm;
  for (const auto& [id, c] : fit.centres) lm[id] = 0;
  for (auto& [id, c] : lm) {
    c = col;
    col += 2;
  }
  return lm;
}

/// The readings' rows of the design.
void designReadingRows(const JointResult& fit, const std::vector<ReadingRow>& rs,
                       const JointConfig& cfg, const std::map<int, int>& lm, Design& x,
                       DesignEntries& e) {
  const int pose0 = e.pose0;
  const int na = fit.model.bias.order() + 1;
  const int n = static_cast<int>(rs.size());
  double tmean = 0.0;
  x.tmin = std::numeric_limits<double>::infinity();
  x.tmax = -x.tmin;
  for (const auto& r : rs) {
    tmean += static_cast<double>(r.r.scan) / static_cast<double>(n);
    x.tmin = std::min(x.tmin, static_cast<double>(r.r.scan));
    x.tmax = std::max(x.tmax, static_cast<double>(r.r.scan));
  }
  for (int i = 0; i < n; ++i) {
    const auto& r = rs[static_cast<std::size_t>(i)].r;
    x.w(i) = 1.0 / (r.sigma_m * r.sigma_m);
    const Pose2& ps = fit.poses[r.stop];
    const auto& c = fit.centres.at(r.landmark);
    const RayGradient g =
        rayGradient(ps.x_m, ps.y_m, ps.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(),
                    c.y(), fit.radius_m);
    const double fp = fit.model.bias.derivative(g.d);
    double v = 1.0;
    for (int a = 0; a < na; ++a) {
      e.j.emplace_back(i, a, v);
      v *= g.d;
    }
    if (cfg.estimate_radius) e.j.emplace_back(i, na, fp * g.dr);
    const int cc = lm.at(r.landmark);
    e.j.emplace_back(i, cc, fp * g.dcx);
    e.j.emplace_back(i, cc + 1, fp * g.dcy);
    const int slot = e.slot[r.stop];
    const int pc = pose0 + e.stride * slot;
    e.j.emplace_back(i, pc, -fp * g.dcx);
    e.j.emplace_back(i, pc + 1, -fp * g.dcy);
    if (e.stride == 3) e.j.emplace_back(i, pc + 2, fp * g.da);
    const int li = static_cast<int>(std::distance(lm.begin(), lm.find(r.landmark)));
    if (li > 0) e.lm.emplace_back(i, li - 1, 1.0);
    e.head.emplace_back(i, slot, fp * g.da);
    x.x_angle(i, 0) = fp * g.da;
    x.x_drift(i, 0) = static_cast<double>(r.scan) - tmean;
    x.x_inc(i, 0) = 1.0 - r.cos_incidence;
  }
}

/// The rows of the motion prior (a continuous recording) on the poses with readings
/// (`stop_of_slot`, in order): the first one's prior, then the odometry from each to the next
/// (odometryStep: the steps in between composed, their variances added up), three rows each on
/// the two poses' columns x, y, heading; the odometry scale's column is their derivative by it.
void designMotionRows(const LandmarkObservations& obs, const JointResult& fit,
                      const JointConfig& cfg, int row0, Design& x, DesignEntries& e) {
  const std::vector<std::size_t>& stop_of_slot = e.stop_of_slot;
  const int pose0 = e.pose0;
  if (stop_of_slot.empty()) return;
  const double inv_s = 1.0 / cfg.sigma_s_m, inv_psi = 1.0 / cfg.sigma_psi_rad;
  e.j.emplace_back(row0, pose0, inv_s);
  e.j.emplace_back(row0 + 1, pose0 + 1, inv_s);
  e.j.emplace_back(row0 + 2, pose0 + 2, inv_psi);
  for (std::size_t k = 1; k < stop_of_slot.size(); ++k) {
    const OdometryStep o = odometryStep(obs, fit, cfg, stop_of_slot[k - 1], stop_of_slot[k]);
    const int row = row0 + 3 * static_cast<int>(k), ca = pose0 + 3 * static_cast<int>(k - 1),
              cb = ca + 3;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        if (o.ja(a, b) != 0.0) e.j.emplace_back(row + a, ca + b, o.ja(a, b));
        if (o.jb(a, b) != 0.0) e.j.emplace_back(row + a, cb + b, o.jb(a, b));
      }
    // The odometry scale: d(residual)/d(s) = -(dx, dy) / sd.
    const Pose2 step =
        stepBetween(obs.commanded[stop_of_slot[k - 1]], obs.commanded[stop_of_slot[k]]);
    x.x_scale(row, 0) = -step.x_m * o.inv_t;
    x.x_scale(row + 1, 0) = -step.y_m * o.inv_t;
  }
}

Design linearisedDesign(const LandmarkObservations& obs, const JointResult& fit,
                        const std::vector<ReadingRow>& rs, const JointConfig& cfg) {
  const int na = fit.model.bias.order() + 1;
  const std::map<int, int> lm = centreColumns(fit, na + (cfg.estimate_radius ? 1 : 0));
  // Under the motion prior a pose's heading is a nuisance parameter too: the baseline refines
  // it, so an effect the headings absorb (an angle offset) is known only as well as the odometry
  // steps say. The poses without readings are composed into the steps between those with (a dense
  // design over every pose of a long log does not fit in memory).
  const bool motion =
      fit.motion_prior && cfg.effects.estimate_heading && obs.commanded.size() >= fit.poses.size();
  std::vector<bool> seen(fit.poses.size(), false);
  for (const auto& r : rs) seen[r.r.stop] = true;
  DesignEntries e;
  e.stride = motion ? 3 : 2;
  e.slot.assign(fit.poses.size(), -1);
  std::vector<std::size_t>& stop_of_slot = e.stop_of_slot;
  for (std::size_t k = 0; k < seen.size(); ++k)
    if (seen[k]) {
      e.slot[k] = static_cast<int>(stop_of_slot.size());
      stop_of_slot.push_back(k);
    }
  const int k_stops = static_cast<int>(stop_of_slot.size());
  const int pose0 = na + (cfg.estimate_radius ? 1 : 0) + 2 * static_cast<int>(lm.size());
  e.pose0 = pose0;
  const int p = pose0 + e.stride * k_stops;
  const int n = static_cast<int>(rs.size());
  const int rows_total = n + e.stride * k_stops;
  Design x;
  x.landmarks = lm.size();
  x.w = Eigen::VectorXd::Ones(rows_total);
  x.x_drift = Eigen::MatrixXd::Zero(rows_total, 1), x.x_angle = x.x_drift, x.x_inc = x.x_drift,
  x.x_scale = x.x_drift;
  e.j.reserve(static_cast<std::size_t>(n) * static_cast<std::size_t>(na + 5) +
              2 * static_cast<std::size_t>(k_stops));
  designReadingRows(fit, rs, cfg, lm, x, e);
  const Pose2& c0 = obs.commanded.front();
  if (motion) designMotionRows(obs, fit, cfg, n, x, e);
  for (int k = 0; k < k_stops && !motion; ++k) {
    const double inv = 1.0 / cfg.sigma_s_m;
    const Pose2& c = obs.commanded[stop_of_slot[static_cast<std::size_t>(k)]];
    e.j.emplace_back(n + 2 * k, pose0 + 2 * k, inv);
    e.j.emplace_back(n + 2 * k + 1, pose0 + 2 * k + 1, inv);
    x.x_scale(n + 2 * k, 0) = -(c.x_m - c0.x_m) * inv;
    x.x_scale(n + 2 * k + 1, 0) = -(c.y_m - c0.y_m) * inv;
  }
  x.j.resize(rows_total, p);
  x.j.setFromTriplets(e.j.begin(), e.j.end());
  x.x_lm.resize(rows_total, std::max<int>(static_cast<int>(lm.size()) - 1, 1));
  x.x_lm.setFromTriplets(e.lm.begin(), e.lm.end());
  x.x_head.resize(rows_total, k_stops);
  x.x_head.setFromTriplets(e.head.begin(), e.head.end());
  return x;
}

/// The nuisance parameters' information, factorised once for every mean-type effect.
struct Nuisance {
  Design::Sparse jw;  ///< J^T W
  /// of J^T W J with a relative ridge (dense: pivoted, for the nearly singular)
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
};

Nuisance nuisanceInformation(const Design& x) {
  Nuisance nu;
  nu.jw = x.j.transpose() * x.w.asDiagonal();
  Eigen::MatrixXd h = Eigen::MatrixXd(nu.jw * x.j);
  // A ridge relative to each parameter's own information: an absolute one (scaled by the
  // largest diagonal) would pin the weakly informed nuisance directions and make an effect
  // that they absorb exactly (a step-length error with the radius free) look estimable.
  h.diagonal().array() *= 1.0 + 1e-9;
  h.diagonal().array() += 1e-300;
  nu.ldlt.compute(h);
  return nu;
}

/// A mean-type effect with columns `xe` (sparse or dense): information left after profiling the
/// nuisance out.
template <class Columns>
Identifiability meanEffectIdentifiability(const Design& x, const Nuisance& nu, const Columns& xe,
                                          double ref) {
  Identifiability id;
  id.ref = ref;
  const Eigen::MatrixXd raw = Eigen::MatrixXd(xe.transpose() * x.w.asDiagonal() * xe);
  const Eigen::MatrixXd c = Eigen::MatrixXd(nu.jw * xe);
  Eigen::MatrixXd eff = raw - c.transpose() * nu.ldlt.solve(c);
  const double tr = raw.trace();
  id.ratio = tr > 0.0 ? std::clamp(eff.trace() / tr, 0.0, 1.0) : 0.0;
  // Standard errors: diagonal of I_eff^-1 (a small ridge keeps a singular I_eff finite and huge).
  eff.diagonal().array() += 1e-12 * (raw.diagonal().array().abs().maxCoeff() + 1e-300);
  const Eigen::MatrixXd cov = eff.ldlt().solve(Eigen::MatrixXd::Identity(eff.rows(), eff.cols()));
  double s = 0.0;
  for (Eigen::Index i = 0; i < cov.rows(); ++i) s += std::max(cov(i, i), 0.0);
  id.se = std::sqrt(s / static_cast<double>(cov.rows()));
  if (!(tr > 0.0)) id.se = std::numeric_limits<double>::infinity();
  return id;
}

/// A variance-type effect: the spread of its covariate beyond a constant (sigma_e).
template <class Covariate>
Identifiability covariateSpreadIdentifiability(const std::vector<ReadingRow>& rs,
                                               Covariate covariate, double ref) {
  const int n = static_cast<int>(rs.size());
  double m = 0.0, m2 = 0.0;
  for (const auto& r : rs) {
    const double g = covariate(r.r);
    m += g / static_cast<double>(n);
    m2 += g * g / static_cast<double>(n);
  }
  Identifiability id;
  id.ratio = std::clamp((m2 - m * m) / (m2 + 1e-4), 0.0, 1.0);
  // sigma of the exponent: 1 / sqrt(2 n var(g)) (Fisher information of a log-sigma slope).
  const double v = std::max(m2 - m * m, 0.0);
  id.se = v > 0.0 ? 1.0 / std::sqrt(2.0 * static_cast<double>(n) * v)
                  : std::numeric_limits<double>::infinity();
  id.ref = ref;
  return id;
}

}  // namespace

std::map<Effect, Identifiability> identifiability(const LandmarkObservations& obs,
                                                  const JointResult& fit,
                                                  const std::vector<ReadingRow>& rs,
                                                  const JointConfig& cfg) {
  const Design x = linearisedDesign(obs, fit, rs, cfg);
  const Nuisance nu = nuisanceInformation(x);
  std::map<Effect, Identifiability> out;
  if (x.landmarks >= 2)
    out[Effect::landmark_bias] = meanEffectIdentifiability(x, nu, x.x_lm, 0.01);
  else
    out[Effect::landmark_bias] =
        Identifiability{0.0, std::numeric_limits<double>::infinity(), 0.01};
  out[Effect::heading_error] = meanEffectIdentifiability(x, nu, x.x_head, deg2rad(1.0));
  out[Effect::angle_offset] = meanEffectIdentifiability(x, nu, x.x_angle, deg2rad(1.0));
  out[Effect::range_drift] =
      meanEffectIdentifiability(x, nu, x.x_drift, x.tmax > x.tmin ? 0.01 / (x.tmax - x.tmin) : 0.0);
  out[Effect::incidence_bias] = meanEffectIdentifiability(x, nu, x.x_inc, 0.01);
  out[Effect::odometry_scale] = meanEffectIdentifiability(x, nu, x.x_scale, 0.01);
  out[Effect::incidence_noise] = covariateSpreadIdentifiability(
      rs, [](const JointReading& r) { return -std::log(r.cos_incidence); }, 0.5);
  out[Effect::dark_surface] = covariateSpreadIdentifiability(
      rs, [](const JointReading& r) { return r.darkness; }, 0.5);
  out[Effect::range_noise_law] = covariateSpreadIdentifiability(
      rs, [&](const JointReading& r) { return std::log(std::max(fit.model.bias(r.d_m), 1e-3)); },
      0.5);
  std::size_t edges = 0;
  for (const auto& r : rs) edges += r.r.edge;
  const bool both = edges >= 10 && rs.size() - edges >= 10;
  out[Effect::mixed_pixels] =
      Identifiability{both ? 1.0 : 0.0, both ? 0.0 : std::numeric_limits<double>::infinity(), 0.02};
  // Student-t noise, parameter 1 / nu (0: Gaussian). Its score at the null is He4(z) / 4 of the
  // standardised residual (the t's log-density to first order in 1 / nu), orthogonal to the
  // location and scale terms, of variance 24 / 16: information 1.5 per reading. Smallest worth
  // naming: nu = 20.
  const double tails_se = rs.empty() ? std::numeric_limits<double>::infinity()
                                     : 1.0 / std::sqrt(1.5 * static_cast<double>(rs.size()));
  out[Effect::heavy_tails] = Identifiability{1.0, tails_se, 0.05};
  return out;
}

}  // namespace lidarcal::diagnosis::sequence
