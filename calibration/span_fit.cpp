// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/span_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include <Eigen/Dense>

#include "calibration/inversion.hpp"
#include "common/pose2.hpp"
#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

/// alpha of the model of `order` from its free coefficients theta (order 0: alpha_1 fixed at 1).
std::vector<double> alphaOf(int order, const Eigen::VectorXd& theta) {
  if (order == 0) return {theta(0), 1.0};
  return std::vector<double>(theta.data(), theta.data() + theta.size());
}

/// Free coefficients of the identity f(d) = d.
Eigen::VectorXd identityTheta(int order) {
  if (order == 0) return Eigen::VectorXd::Zero(1);
  Eigen::VectorXd t = Eigen::VectorXd::Zero(order + 1);
  t(1) = 1.0;
  return t;
}

/// Every entry's error (what the sensor says with f - what was measured, metres) and their
/// covariance under f; ok is false when some wall cannot be placed.
struct Residuals {
  bool ok = true;
  Eigen::VectorXd error_m;
  Eigen::MatrixXd covariance;
};

Residuals residuals(const SpanProblem& p, const BiasPolynomial& f) {
  Residuals out;
  const std::size_t m = p.entries();
  out.error_m = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m));
  out.covariance =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  std::vector<WallDistance> walls;
  walls.reserve(p.walls.size());
  for (const SpanWall& w : p.walls) {
    walls.push_back(wallDistance(w, f));
    out.ok = out.ok && walls.back().ok;
  }
  if (!out.ok) return out;
  for (std::size_t k = 0; k < p.spans.size(); ++k) {
    const auto& s = p.spans[k];
    const auto i = static_cast<Eigen::Index>(k);
    out.error_m(i) = walls[s.wall_a].distance_m + walls[s.wall_b].distance_m - s.distance_m;
    out.covariance(i, i) = s.sigma_m * s.sigma_m;
    // Spans that share a wall share the error of its distance.
    for (std::size_t l = 0; l < p.spans.size(); ++l)
      for (std::size_t w : {s.wall_a, s.wall_b})
        if (w == p.spans[l].wall_a || w == p.spans[l].wall_b)
          out.covariance(i, static_cast<Eigen::Index>(l)) += walls[w].variance_m2;
  }
  for (std::size_t e = 0; e < p.tapes.size(); ++e) {
    const TapeEntry& t = p.tapes[e];
    const auto i = static_cast<Eigen::Index>(p.spans.size() + e);
    const double n = static_cast<double>(t.d_m.size());
    double fbar = 0.0, ybar = 0.0, dbar = 0.0;
    for (std::size_t j = 0; j < t.d_m.size(); ++j)
      fbar += f(t.d_m[j]) / n, ybar += t.y_m[j] / n, dbar += t.d_m[j] / n;
    double s2 = 0.0;
    for (std::size_t j = 0; j < t.d_m.size(); ++j)
      s2 += std::pow(t.y_m[j] - f(t.d_m[j]) - (ybar - fbar), 2) / std::max(n - 1.0, 1.0);
    const double slope = std::max(f.derivative(dbar), 1e-3);
    out.error_m(i) = (ybar - fbar) / slope;
    out.covariance(i, i) =
        t.sigma_m * t.sigma_m +
        s2 / (static_cast<double>(std::max<std::size_t>(t.beams, 1)) * slope * slope);
  }
  return out;
}

/// The rows and columns of `use`.
Eigen::VectorXd select(const Eigen::VectorXd& v, const std::vector<bool>& use) {
  std::vector<double> out;
  for (std::size_t k = 0; k < use.size(); ++k)
    if (use[k]) out.push_back(v(static_cast<Eigen::Index>(k)));
  return Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

Eigen::MatrixXd select(const Eigen::MatrixXd& a, const std::vector<bool>& use) {
  std::vector<Eigen::Index> rows;
  for (std::size_t k = 0; k < use.size(); ++k)
    if (use[k]) rows.push_back(static_cast<Eigen::Index>(k));
  Eigen::MatrixXd out(rows.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < rows.size(); ++j)
      out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = a(rows[i], rows[j]);
  return out;
}

/// The used entries' errors, their whitening (inverse Cholesky factor) and the Jacobian of the
/// errors in the free coefficients (central differences) at theta.
struct Linearised {
  bool ok = false;
  Eigen::VectorXd error_m;   // all entries
  Eigen::VectorXd white;     // used entries, whitened
  Eigen::MatrixXd jacobian;  // used entries, whitened
};

Linearised linearise(const SpanProblem& p, int order, const Eigen::VectorXd& theta,
                     const std::vector<bool>& use) {
  Linearised out;
  const Residuals r = residuals(p, BiasPolynomial{alphaOf(order, theta)});
  if (!r.ok) return out;
  const Eigen::LLT<Eigen::MatrixXd> llt(select(r.covariance, use));
  if (llt.info() != Eigen::Success) return out;
  out.error_m = r.error_m;
  out.white = llt.matrixL().solve(select(r.error_m, use));
  out.jacobian.resize(out.white.size(), theta.size());
  for (Eigen::Index j = 0; j < theta.size(); ++j) {
    const double h = 1e-6;
    Eigen::VectorXd up = theta, down = theta;
    up(j) += h;
    down(j) -= h;
    const Residuals a = residuals(p, BiasPolynomial{alphaOf(order, up)});
    const Residuals b = residuals(p, BiasPolynomial{alphaOf(order, down)});
    if (!a.ok || !b.ok) return out;
    out.jacobian.col(j) =
        llt.matrixL().solve(select(Eigen::VectorXd((a.error_m - b.error_m) / (2.0 * h)), use));
  }
  out.ok = true;
  return out;
}

/// Whether the whitened Jacobian has full column rank (columns scaled to unit length first).
bool fullRank(const Eigen::MatrixXd& jacobian) {
  if (jacobian.rows() < jacobian.cols()) return false;
  Eigen::MatrixXd scaled = jacobian;
  for (Eigen::Index j = 0; j < scaled.cols(); ++j) {
    const double norm = scaled.col(j).norm();
    if (!(norm > 0.0)) return false;
    scaled.col(j) /= norm;
  }
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(scaled).singularValues();
  return sv(sv.size() - 1) > 1e-6 * sv(0);
}

}  // namespace

std::string SpanProblem::name(std::size_t k) const {
  return k < spans.size() ? "spans[" + std::to_string(spans[k].entry) + "]"
                          : "distances[" + std::to_string(tapes[k - spans.size()].entry) + "]";
}

std::vector<std::size_t> SpanProblem::groups() const {
  std::vector<std::size_t> out;
  std::map<std::pair<std::size_t, std::size_t>, std::size_t> pair_group;
  std::size_t next = 0;
  for (const Span& s : spans) {
    const auto key = std::minmax(s.wall_a, s.wall_b);
    const auto it = pair_group.emplace(key, next).first;
    if (it->second == next) ++next;
    out.push_back(it->second);
  }
  for (std::size_t e = 0; e < tapes.size(); ++e) out.push_back(next++);
  return out;
}

WallDistance wallDistance(const SpanWall& wall, const BiasPolynomial& f) {
  WallDistance out;
  const std::size_t n = wall.beams.size();
  if (n < 3) return out;
  double p = wall.distance_m, normal = wall.normal_rad;
  Eigen::MatrixXd jac(static_cast<Eigen::Index>(n), 2);
  Eigen::VectorXd r(static_cast<Eigen::Index>(n));
  auto linearise_at = [&](double p_m, double n_rad) {
    for (std::size_t b = 0; b < n; ++b) {
      const double u = wall.beams[b].angle_rad - n_rad, c = std::max(std::cos(u), 0.05),
                   d = p_m / c;
      const auto i = static_cast<Eigen::Index>(b);
      r(i) = wall.beams[b].reading_m - f(d);
      jac(i, 0) = -f.derivative(d) / c;
      // d = p / cos(phi - n): dd/dn = -d tan(phi - n)
      jac(i, 1) = f.derivative(d) * d * std::tan(u);
    }
  };
  for (int it = 0; it < 50; ++it) {
    linearise_at(p, normal);
    const Eigen::Vector2d step = (jac.transpose() * jac).ldlt().solve(-jac.transpose() * r);
    if (!step.allFinite()) return out;
    p += step(0);
    normal += step(1);
    if (!(p > 0.0)) return out;
    if (std::abs(step(0)) < 1e-12 && std::abs(step(1)) < 1e-12) break;
  }
  linearise_at(p, normal);
  const Eigen::Matrix2d info = jac.transpose() * jac;
  const double s2 = n > 2 ? r.squaredNorm() / static_cast<double>(n - 2) : 0.0;
  const Eigen::Matrix2d cov = info.inverse() * s2;
  if (!cov.allFinite()) return out;
  out.ok = true;
  out.distance_m = p;
  out.normal_rad = wrapAngle(normal);
  out.variance_m2 = cov(0, 0);
  return out;
}

SpanProblem spanProblem(const SpanReadings& spans, const Reference& ref,
                        const std::vector<KnownReading>& tape) {
  SpanProblem p;
  p.walls = spans.walls;
  for (const SpanMatch& m : spans.matches) {
    if (!m.ok())
      throw std::invalid_argument("spanProblem: spans[" + std::to_string(m.entry) +
                                  "] was not matched");
    p.spans.push_back({m.entry, m.stop, m.wall_a, m.wall_b, ref.spans.at(m.entry).distance_m,
                       ref.spans.at(m.entry).sigma_m});
  }
  std::map<std::size_t, TapeEntry> by_entry;
  std::map<std::size_t, std::set<std::uint32_t>> beams;
  for (const KnownReading& r : tape) {
    TapeEntry& t = by_entry[r.entry];
    t.entry = r.entry;
    t.stop = r.stop;
    t.d_m.push_back(r.d_m);
    t.y_m.push_back(r.y_m);
    beams[r.entry].insert(r.beam);
  }
  for (auto& [entry, t] : by_entry) {
    t.reference_m = ref.distances.at(entry).distance_m;
    t.sigma_m = ref.distances.at(entry).sigma_m;
    t.beams = beams[entry].size();
    p.tapes.push_back(std::move(t));
  }
  return p;
}

Eigen::VectorXd entryErrors(const SpanProblem& problem, const BiasPolynomial& f) {
  const Residuals r = residuals(problem, f);
  return r.ok ? r.error_m : Eigen::VectorXd();
}

SpanModelFit fitSpanModel(const SpanProblem& problem, int order, const std::vector<bool>& use) {
  if (use.size() != problem.entries())
    throw std::invalid_argument("fitSpanModel: use has the wrong size");
  SpanModelFit fit;
  fit.order = order;
  Eigen::VectorXd theta = identityTheta(order);
  const auto used = static_cast<std::size_t>(std::count(use.begin(), use.end(), true));
  Linearised lin = linearise(problem, order, theta, use);
  if (!lin.ok || !fullRank(lin.jacobian)) return fit;
  for (int it = 0; it < 30; ++it) {
    const Eigen::VectorXd step = (lin.jacobian.transpose() * lin.jacobian)
                                     .ldlt()
                                     .solve(-lin.jacobian.transpose() * lin.white);
    if (!step.allFinite()) return fit;
    theta += step;
    lin = linearise(problem, order, theta, use);
    if (!lin.ok) return fit;
    if (step.cwiseAbs().maxCoeff() < 1e-10) break;
  }
  const Eigen::MatrixXd info = lin.jacobian.transpose() * lin.jacobian;
  fit.identifiable = fullRank(lin.jacobian);
  fit.alpha = alphaOf(order, theta);
  fit.chi2 = lin.white.squaredNorm();
  fit.dof = used - static_cast<std::size_t>(theta.size());
  const double birge = fit.dof > 0 ? std::max(1.0, fit.chi2 / static_cast<double>(fit.dof)) : 1.0;
  const Eigen::MatrixXd cov = info.inverse() * birge;
  fit.covariance = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(fit.alpha.size()),
                                         static_cast<Eigen::Index>(fit.alpha.size()));
  fit.covariance.topLeftCorner(cov.rows(), cov.cols()) = cov;
  fit.error_m = lin.error_m;
  return fit;
}

}  // namespace lidarcal::calibration
