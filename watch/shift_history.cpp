// SPDX-License-Identifier: BSD-3-Clause
#include "watch/shift_history.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <boost/math/distributions/fisher_f.hpp>

namespace lidarcal::watch {

namespace {
constexpr double kQ = 2.0;  // coordinates of a shift
}

double fTail(double f, double d1, double d2) {
  if (!(f > 0.0) || !std::isfinite(f)) return f > 0.0 ? 0.0 : 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::fisher_f(d1, d2), f));
}

ShiftHistory::ShiftHistory(std::size_t capacity) : capacity_(capacity) {
  if (capacity_ < 2) throw std::invalid_argument("ShiftHistory: capacity must be >= 2");
}

void ShiftHistory::add(const Shift& shift) {
  shifts_.push_back(shift);
  while (shifts_.size() > capacity_) shifts_.pop_front();
}

namespace {

/// Records that share tau^2 and phi^2, each with a mean of its own.
using Groups = std::vector<const std::deque<Shift>*>;

struct Pooled {
  std::vector<Eigen::Vector2d> b;  // b^ of each group
  std::vector<Eigen::Matrix2d> v;  // V_b of each group
  double tau2 = 0.0;               // the spread between checks, m^2
  double phi2 = 1.0;               // the scale
  double nu = 0.0;                 // its degrees of freedom: q (checks - groups)
  double rss = 0.0;                // the weighted residual sum of squares
  double log_det = 0.0;            // sum log|C_j + tau^2 I| + sum over groups log|sum W_j|
};

std::size_t checks(const Groups& groups) {
  std::size_t n = 0;
  for (const auto* g : groups) n += g->size();
  return n;
}

Pooled gls(const Groups& groups, double tau2) {
  Pooled p;
  p.tau2 = tau2;
  p.log_det = 0.0;
  double rss = 0.0;
  for (const auto* shifts : groups) {
    Eigen::Matrix2d w_sum = Eigen::Matrix2d::Zero();
    Eigen::Vector2d ws_sum = Eigen::Vector2d::Zero();
    for (const Shift& x : *shifts) {
      const Eigen::Matrix2d c = x.c + tau2 * Eigen::Matrix2d::Identity();
      const Eigen::Matrix2d w = c.inverse();
      w_sum += w;
      ws_sum += w * x.s;
      p.log_det += std::log(c.determinant());
    }
    const Eigen::Matrix2d v = w_sum.inverse();
    const Eigen::Vector2d b = v * ws_sum;
    p.log_det -= std::log(v.determinant());  // + log det(sum W)
    for (const Shift& x : *shifts) {
      const Eigen::Vector2d r = x.s - b;
      rss += r.dot((x.c + tau2 * Eigen::Matrix2d::Identity()).inverse() * r);
    }
    p.b.push_back(b);
    p.v.push_back(v);
  }
  p.nu = kQ * (static_cast<double>(checks(groups)) - static_cast<double>(groups.size()));
  p.phi2 = rss / p.nu;
  p.rss = rss;
  return p;
}

Pooled pool(const Groups& groups) {
  const std::size_t n = checks(groups);
  if (n < groups.size() + 1) throw std::logic_error("ShiftHistory: too few checks");
  // tau^2 by restricted maximum likelihood: minimise log|C_j + tau^2 I| summed, + log|sum W_j|,
  // + the weighted residual sum of squares, over a grid of 0 and 60 values from 1e-4 to 1e2 times
  // the checks' typical variance, then a golden-section refinement between the grid's
  // neighbours. Deterministic.
  double typical = 0.0;
  for (const auto* g : groups)
    for (const Shift& x : *g) typical += 0.5 * x.c.trace() / static_cast<double>(n);
  auto objective = [&groups](double t) {
    const Pooled p = gls(groups, t);
    return p.log_det + p.rss;
  };
  std::vector<double> grid = {0.0};
  for (int i = 0; i <= 60; ++i) grid.push_back(typical * std::pow(10.0, -4.0 + 6.0 * i / 60.0));
  std::size_t best = 0;
  double best_value = objective(0.0);
  for (std::size_t i = 1; i < grid.size(); ++i)
    if (const double v = objective(grid[i]); v < best_value) best = i, best_value = v;
  double lo = grid[best == 0 ? 0 : best - 1], hi = grid[std::min(best + 1, grid.size() - 1)];
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 40 && hi - lo > 1e-6 * typical; ++it) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    (objective(a) < objective(b) ? hi : lo) = (objective(a) < objective(b) ? b : a);
  }
  const double tau2 = objective(0.5 * (lo + hi)) < best_value ? 0.5 * (lo + hi) : grid[best];
  return gls(groups, tau2);
}

/// The F test of `statistic` on q and the pooled record's degrees of freedom.
FTest fTest(double statistic, const Pooled& p) {
  FTest t;
  t.dof1 = kQ;
  t.dof2 = p.nu;
  t.statistic = statistic;
  t.p = fTail(t.statistic, t.dof1, t.dof2);
  return t;
}

}  // namespace

FTest ShiftHistory::change(const Shift& now) const {
  const Pooled p = pool({&shifts_});
  const Eigen::Vector2d r = now.s - p.b[0];
  const Eigen::Matrix2d c = now.c + p.tau2 * Eigen::Matrix2d::Identity() + p.v[0];
  return fTest(r.dot(c.inverse() * r) / (kQ * p.phi2), p);
}

FTest ShiftHistory::absolute(const Eigen::Matrix2d& model_covariance) const {
  const Pooled p = pool({&shifts_});
  return fTest(p.b[0].dot((p.phi2 * p.v[0] + model_covariance).inverse() * p.b[0]) / kQ, p);
}

FTest ShiftHistory::sameMean(const ShiftHistory& earlier) const {
  const Pooled p = pool({&earlier.shifts_, &shifts_});
  const Eigen::Vector2d d = p.b[1] - p.b[0];
  return fTest(d.dot((p.v[0] + p.v[1]).inverse() * d) / (kQ * p.phi2), p);
}

Eigen::Vector2d ShiftHistory::mean() const { return pool({&shifts_}).b[0]; }

}  // namespace lidarcal::watch
