// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/sequence/statistics.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "common/pose2.hpp"
#include "common/stats_util.hpp"
#include "diagnosis/sequence/pose_uncertainty.hpp"
#include "diagnosis/stats.hpp"

namespace lidarcal::diagnosis::sequence {
namespace {

/// Score of a mean-type effect with covariate x (metres of reading per unit parameter).
double meanScore(const std::vector<ReadingRow>& rs, const std::vector<double>& x) {
  std::vector<double> psi(rs.size()), xs(rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) {
    psi[i] = rs[i].psi;
    xs[i] = x[i] / rs[i].r.sigma_m;
  }
  return diagnosis::meanScore(psi, xs);
}

/// Score of a variance-type effect with covariate g (log of the factor on sigma per unit).
double spreadScore(const std::vector<ReadingRow>& rs, const std::vector<double>& g) {
  std::vector<double> z(rs.size());
  for (std::size_t i = 0; i < rs.size(); ++i) z[i] = rs[i].z;
  return diagnosis::spreadScore(z, g);
}

/// Sum over groups of (group score)^2 / information, with the overall mean removed (the bias
/// polynomial's alpha_0 absorbs it when `centre`), as a cube root (Wilson-Hilferty).
double groupChi2(const std::vector<ReadingRow>& rs, const std::vector<int>& group,
                 const std::vector<double>& x, bool centre) {
  std::map<int, std::pair<double, double>> g;  // score, information
  double u_all = 0.0, i_all = 0.0;
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const double xs = x[i] / rs[i].r.sigma_m;
    g[group[i]].first += rs[i].psi * xs;
    g[group[i]].second += xs * xs;
    u_all += rs[i].psi * xs;
    i_all += xs * xs;
  }
  double chi2 = 0.0;
  int n = 0;
  for (const auto& [k, v] : g) {
    if (!(v.second > 0.0)) continue;
    const double u = centre && i_all > 0.0 ? v.first - v.second * u_all / i_all : v.first;
    chi2 += u * u / v.second;
    ++n;
  }
  return cubeRootChi2(chi2, std::max(centre ? n - 1 : n, 1));
}

/// Residuals of a polynomial trend in x of order up to `order` (weighted least squares), so
/// that a covariate is tested beyond what the bias polynomial already absorbs.
std::vector<double> orthogonalise(const std::vector<double>& x, const std::vector<double>& d,
                                  const std::vector<double>& w, int order) {
  const int p = order + 1;
  Eigen::MatrixXd a(static_cast<Eigen::Index>(x.size()), p);
  Eigen::VectorXd b(static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double sw = std::sqrt(w[i]);
    double v = 1.0;
    for (int j = 0; j < p; ++j) {
      a(static_cast<Eigen::Index>(i), j) = sw * v;
      v *= d[i];
    }
    b(static_cast<Eigen::Index>(i)) = sw * x[i];
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  std::vector<double> out(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    double v = 1.0, fit = 0.0;
    for (int j = 0; j < p; ++j) {
      fit += c(j) * v;
      v *= d[i];
    }
    out[i] = x[i] - fit;
  }
  return out;
}

/// Range and incidence: the residuals' trend beyond the bias polynomial, and their spread
/// (noise law). `d`: predicted distances, `w`: weights 1 / sigma^2.
void rangeStatistics(const JointResult& fit, const std::vector<ReadingRow>& rs,
                     const std::vector<double>& d, const std::vector<double>& w, Statistics& st) {
  const std::size_t n = rs.size();
  std::vector<double> x(n), g(n);
  const int order = fit.model.bias.order();
  for (std::size_t i = 0; i < n; ++i) x[i] = std::pow(d[i], order + 1);
  st["residual_vs_range"] = meanScore(rs, orthogonalise(x, d, w, order));
  for (std::size_t i = 0; i < n; ++i)
    g[i] = std::log(std::max(std::abs(fit.model.bias(d[i])), 1e-3));
  st["spread_vs_range"] = spreadScore(rs, g);
  for (std::size_t i = 0; i < n; ++i) x[i] = 1.0 - rs[i].r.cos_incidence;
  st["residual_vs_incidence"] = meanScore(rs, orthogonalise(x, d, w, 0));
  for (std::size_t i = 0; i < n; ++i) g[i] = -std::log(rs[i].r.cos_incidence);
  st["spread_vs_incidence"] = spreadScore(rs, g);
  for (std::size_t i = 0; i < n; ++i) g[i] = rs[i].r.darkness;
  st["spread_vs_intensity"] = spreadScore(rs, g);
}

/// Position within the object: outermost beams against the others.
void edgeStatistics(const std::vector<ReadingRow>& rs, Statistics& st) {
  double pos_edge = 0, neg_edge = 0, n_edge = 0, pos_in = 0, neg_in = 0, n_in = 0, s_edge = 0,
         s_in = 0;
  for (const auto& r : rs) {
    const double z2 = std::min(r.z * r.z, kClip * kClip);
    if (r.r.edge) {
      n_edge += 1;
      pos_edge += r.z > kClip;
      neg_edge += r.z < -kClip;
      s_edge += z2;
    } else {
      n_in += 1;
      pos_in += r.z > kClip;
      neg_in += r.z < -kClip;
      s_in += z2;
    }
  }
  const double expected = n_in > 0 ? n_edge * (pos_in - neg_in) / n_in : 0.0;
  st["edge_excess"] = n_edge > 0 ? (pos_edge - neg_edge - expected) / std::sqrt(n_edge) : 0.0;
  st["edge_vs_centre_spread"] = (n_edge > 0 && n_in > 0) ? s_edge / n_edge - s_in / n_in : 0.0;
}

/// Landmark and stop identity (offsets beyond the common bias), rotations per stop (heading
/// errors) and common (zero-angle offset), time, bearing in the sensor frame.
void groupStatistics(const std::vector<ReadingRow>& rs, const std::vector<double>& d,
                     const std::vector<double>& w, Statistics& st) {
  const std::size_t n = rs.size();
  std::vector<double> x(n), one(n, 1.0);
  std::vector<int> grp(n);
  for (std::size_t i = 0; i < n; ++i) grp[i] = rs[i].r.landmark;
  st["landmark_identity"] = groupChi2(rs, grp, one, true);
  for (std::size_t i = 0; i < n; ++i) grp[i] = static_cast<int>(rs[i].r.stop);
  st["stop_identity"] = groupChi2(rs, grp, one, true);
  for (std::size_t i = 0; i < n; ++i) x[i] = rs[i].dmu_da;
  st["heading_within_stop"] = groupChi2(rs, grp, x, false);
  st["common_rotation"] = meanScore(rs, x);
  double tm = 0.0, tw = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    tm += w[i] * static_cast<double>(rs[i].r.scan);
    tw += w[i];
  }
  for (std::size_t i = 0; i < n; ++i) x[i] = static_cast<double>(rs[i].r.scan) - tm / tw;
  st["residual_vs_time"] = meanScore(rs, x);
  // Bearing in the sensor frame: first harmonics.
  std::vector<double> xc(n), xs(n);
  for (std::size_t i = 0; i < n; ++i) {
    xc[i] = std::cos(rs[i].r.angle_rad);
    xs[i] = std::sin(rs[i].r.angle_rad);
  }
  const double a = meanScore(rs, orthogonalise(xc, d, w, 0)),
               b = meanScore(rs, orthogonalise(xs, d, w, 0));
  st["residual_vs_bearing"] = cubeRootChi2(a * a + b * b, 2.0);
}

/// The refined path against the commanded one, about its centroid: rotated (a zero-angle
/// offset turns the path the data see against the headings) or stretched (step length).
void pathStatistics(const LandmarkObservations& obs, const JointResult& fit, const JointConfig& cfg,
                    Statistics& st) {
  double cx = 0.0, cy = 0.0;
  const std::size_t k_stops = std::min(fit.poses.size(), obs.commanded.size());
  for (std::size_t k = 0; k < k_stops; ++k) {
    cx += obs.commanded[k].x_m / static_cast<double>(k_stops);
    cy += obs.commanded[k].y_m / static_cast<double>(k_stops);
  }
  double rot = 0.0, str = 0.0, info = 0.0;
  for (std::size_t k = 0; k < k_stops; ++k) {
    const double ex = obs.commanded[k].x_m - cx, ey = obs.commanded[k].y_m - cy;
    const double dx = fit.poses[k].x_m - obs.commanded[k].x_m,
                 dy = fit.poses[k].y_m - obs.commanded[k].y_m;
    rot += ex * dy - ey * dx;
    str += ex * dx + ey * dy;
    info += ex * ex + ey * ey;
  }
  st["path_rotation"] = info > 0.0 ? rot / (cfg.sigma_s_m * std::sqrt(info)) : 0.0;
  st["path_scale"] = info > 0.0 ? str / (cfg.sigma_s_m * std::sqrt(info)) : 0.0;
}

/// Sighting bearings: shared shifts within a stop (F ratio of stop means, log).
void bearingStatistics(const LandmarkObservations& obs, const JointResult& fit, Statistics& st) {
  std::map<std::size_t, std::vector<double>> by_stop;
  for (const auto& s : obs.sightings) {
    auto c = fit.centres.find(s.landmark);
    if (c == fit.centres.end() || s.stop >= fit.poses.size()) continue;
    const Pose2& p = fit.poses[s.stop];
    const double predicted = std::atan2(c->second.y() - p.y_m, c->second.x() - p.x_m) - p.yaw_rad -
                             fit.effects.angle_offset_rad;
    by_stop[s.stop].push_back(wrapAngle(s.bearing_rad - predicted));
  }
  double grand = 0.0, total = 0.0;
  for (const auto& [k, v] : by_stop)
    for (double b : v) {
      grand += b;
      total += 1.0;
    }
  grand /= std::max(total, 1.0);
  double between = 0.0, within = 0.0;
  for (const auto& [k, v] : by_stop) {
    double m = 0.0;
    for (double b : v) m += b / static_cast<double>(v.size());
    between += static_cast<double>(v.size()) * (m - grand) * (m - grand);
    for (double b : v) within += (b - m) * (b - m);
  }
  const double dfb = static_cast<double>(by_stop.size()) - 1.0,
               dfw = total - static_cast<double>(by_stop.size());
  st["bearing_within_stop_correlation"] =
      (dfb > 0 && dfw > 0 && within > 0) ? std::log((between / dfb) / (within / dfw)) : 0.0;
}

/// Tails and quantisation.
void shapeStatistics(const std::vector<ReadingRow>& rs, Statistics& st) {
  const std::size_t n = rs.size();
  double m2 = 0.0, m4 = 0.0;
  for (const auto& r : rs) {
    m2 += r.z * r.z;
    m4 += r.z * r.z * r.z * r.z;
  }
  m2 /= static_cast<double>(n);
  m4 /= static_cast<double>(n);
  st["tail_weight"] = m4 / (m2 * m2) - 3.0;
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = rs[i].r.y_m;
  st["quantisation_1mm"] = gridResultant(y, 1e-3);
}

}  // namespace

std::vector<ReadingRow> readingRows(const LandmarkObservations& obs, const JointResult& fit,
                                    const JointConfig& cfg) {
  std::vector<ReadingRow> out;
  for (const auto& r : evaluateJoint(obs, fit, cfg)) {
    ReadingRow w;
    w.r = r;
    w.z = (r.y_m - r.mean_m) / r.sigma_m;
    w.psi = huberPsi(w.z, kClip);
    const Pose2& p = fit.poses[r.stop];
    const auto& c = fit.centres.at(r.landmark);
    const RayGradient g =
        rayGradient(p.x_m, p.y_m, p.yaw_rad + r.angle_rad + fit.effects.angle_offset_rad, c.x(),
                    c.y(), fit.radius_m);
    w.dmu_da = fit.model.bias.derivative(g.d) * g.da;
    out.push_back(w);
  }
  return out;
}

Statistics sequenceStatistics(const LandmarkObservations& obs, const JointResult& fit,
                              const std::vector<ReadingRow>& rs, const JointConfig& cfg) {
  Statistics st;
  const std::size_t n = rs.size();
  if (n == 0) return st;
  std::vector<double> d(n), w(n);
  for (std::size_t i = 0; i < n; ++i) {
    d[i] = rs[i].r.d_m;
    w[i] = 1.0 / (rs[i].r.sigma_m * rs[i].r.sigma_m);
  }
  rangeStatistics(fit, rs, d, w, st);
  edgeStatistics(rs, st);
  groupStatistics(rs, d, w, st);
  pathStatistics(obs, fit, cfg, st);
  bearingStatistics(obs, fit, st);
  shapeStatistics(rs, st);
  return st;
}

}  // namespace lidarcal::diagnosis::sequence
