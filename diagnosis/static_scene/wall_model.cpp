// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/wall_model.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

namespace lidarcal::diagnosis::static_scene {
namespace {

/// The wall model's mean of bin b (u: beam angle from the wall's normal, cu: its cosine, held
/// away from 0).
double wallMean(const BinnedReadings& d, const WallFit& w, std::size_t b, double& u, double& cu) {
  const Line& l = w.lines[static_cast<std::size_t>(d.bins[b].wall)];
  u = d.bins[b].angle - l.theta;
  cu = std::max(std::cos(u), 0.05);
  return w.alpha0 + w.b * (1.0 - cu) + l.p / cu;
}

/// The wall model's least-squares system at its current parameters: Jacobian (alpha_0, b when
/// fitted, then p and theta of each line), residuals and weights of the wall bins.
struct WallSystem {
  /// four entries a row at most: the normal matrix is an arrow
  Eigen::SparseMatrix<double, Eigen::RowMajor> j;
  Eigen::VectorXd r, wt;
};

/// The weighted normal matrix J^T W J (alpha_0 held: its diagonal set to `held_diagonal`).
Eigen::SparseMatrix<double> wallNormal(const WallSystem& s, bool alpha0_free,
                                       double held_diagonal) {
  const Eigen::SparseMatrix<double, Eigen::RowMajor> jw = s.wt.asDiagonal() * s.j;
  Eigen::SparseMatrix<double> h =
      Eigen::SparseMatrix<double>(s.j.transpose()) * Eigen::SparseMatrix<double>(jw);
  if (!alpha0_free) h.coeffRef(0, 0) = held_diagonal;
  return h;
}

/// Residuals and weights of the wall bins (roughness tau2 plus the bin mean's variance).
void wallResiduals(const BinnedReadings& d, const std::vector<BinFit>& f, const WallFit& w,
                   double tau2, WallSystem& s) {
  for (int k = 0; k < static_cast<int>(w.bins.size()); ++k) {
    const std::size_t b = w.bins[static_cast<std::size_t>(k)];
    double u, cu;
    s.r(k) = f[b].m - wallMean(d, w, b, u, cu);
    s.wt(k) = 1.0 / (tau2 + f[b].s2 / f[b].n);
  }
}

/// Gauss-Newton on the wall model at fixed roughness (at most 15 steps); false when a step is
/// not finite.
/// What a wall fit estimates: the incidence term b, the offset alpha_0 (else held), and the
/// walls' roughness tau^2 it weights the bins with.
struct WallTerms {
  bool with_b = false;
  bool alpha0_free = true;
  double tau2 = 0.0;
};

bool wallGaussNewton(const BinnedReadings& d, const std::vector<BinFit>& f, WallFit& w,
                     const WallTerms& terms, WallSystem& s) {
  const bool with_b = terms.with_b, alpha0_free = terms.alpha0_free;
  const double tau2 = terms.tau2;
  const int nb = static_cast<int>(w.bins.size()), nl = static_cast<int>(w.lines.size());
  std::vector<Eigen::Triplet<double>> entries;
  for (int it = 0; it < 15; ++it) {
    entries.clear();
    for (int k = 0; k < nb; ++k) {
      const std::size_t b = w.bins[static_cast<std::size_t>(k)];
      double u, cu;
      const double mu = wallMean(d, w, b, u, cu);
      const Line& l = w.lines[static_cast<std::size_t>(d.bins[b].wall)];
      s.r(k) = f[b].m - mu;
      s.wt(k) = 1.0 / (tau2 + f[b].s2 / f[b].n);
      if (alpha0_free) entries.emplace_back(k, 0, 1.0);
      int c = 1;
      if (with_b) entries.emplace_back(k, c++, 1.0 - cu);
      const int wl = c + 2 * d.bins[b].wall;
      entries.emplace_back(k, wl, 1.0 / cu);
      entries.emplace_back(k, wl + 1, -l.p * std::sin(u) / (cu * cu) - w.b * std::sin(u));
    }
    s.j.setFromTriplets(entries.begin(), entries.end());
    // Sparse: a cluttered room has hundreds of short lines, and a dense normal matrix then
    // costs seconds a step.
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(wallNormal(s, alpha0_free, 1.0));
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::VectorXd step =
        ldlt.solve(Eigen::VectorXd(s.j.transpose() * s.wt.cwiseProduct(s.r)));
    if (!step.allFinite()) return false;
    w.alpha0 += step(0);
    int c = 1;
    if (with_b) w.b += step(c++);
    for (int l = 0; l < nl; ++l) {
      w.lines[static_cast<std::size_t>(l)].p += step(c + 2 * l);
      w.lines[static_cast<std::size_t>(l)].theta += step(c + 2 * l + 1);
    }
    if (step.cwiseAbs().maxCoeff() < 1e-9) break;
  }
  return true;
}

/// Roughness: ML of tau^2 given the residuals (ternary search on log tau).
double wallRoughness(const std::vector<BinFit>& f, const WallFit& w, const Eigen::VectorXd& r) {
  auto ll = [&](double log_tau) {
    const double t2 = std::exp(2.0 * log_tau);
    double s = 0.0;
    for (int k = 0; k < static_cast<int>(w.bins.size()); ++k) {
      const std::size_t b = w.bins[static_cast<std::size_t>(k)];
      const double v = t2 + f[b].s2 / f[b].n;
      s -= 0.5 * (std::log(v) + r(k) * r(k) / v);
    }
    return s;
  };
  const double lt = ternaryMax(ll, std::log(1e-5), std::log(0.5), 60);
  return std::exp(2.0 * lt);
}

/// Final residuals, standard errors and leave-one-out predictive log-likelihoods (the
/// Jacobian is the last Gauss-Newton step's).
void finishWalls(const BinnedReadings& d, const std::vector<BinFit>& f, WallFit& w,
                 const WallTerms& terms, WallSystem& s) {
  const bool with_b = terms.with_b, alpha0_free = terms.alpha0_free;
  const double tau2 = terms.tau2;
  const int nb = static_cast<int>(w.bins.size());
  const auto np = static_cast<int>(s.j.cols());
  wallResiduals(d, f, w, tau2, s);
  // alpha_0 held: no uncertainty, no leverage
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(wallNormal(s, alpha0_free, 1e12));
  if (ldlt.info() != Eigen::Success) return;
  const Eigen::MatrixXd cov = ldlt.solve(Eigen::MatrixXd::Identity(np, np));
  w.alpha0_se = alpha0_free ? std::sqrt(std::max(cov(0, 0), 0.0)) : 0.0;
  if (with_b) w.b_se = std::sqrt(std::max(cov(1, 1), 0.0));
  w.loo_ll.resize(static_cast<std::size_t>(nb));
  w.resid.resize(static_cast<std::size_t>(nb));
  double ss = 0.0;
  for (int k = 0; k < nb; ++k) {
    double quad = 0.0;  // j_k^T cov j_k over the row's few entries
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator a(s.j, k); a; ++a)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator c(s.j, k); c; ++c)
        quad += a.value() * cov(a.col(), c.col()) * c.value();
    const double hii = std::min(s.wt(k) * quad, 0.99);
    const double v = (1.0 / s.wt(k)) / (1.0 - hii);
    const double e = s.r(k) / (1.0 - hii);
    w.loo_ll[static_cast<std::size_t>(k)] = -0.5 * (kLog2Pi + std::log(v) + e * e / v);
    w.in_ll -= 0.5 * (kLog2Pi - std::log(s.wt(k)) + s.r(k) * s.r(k) * s.wt(k));
    w.resid[static_cast<std::size_t>(k)] = s.r(k);
    ss += s.r(k) * s.r(k);
  }
  w.rms = std::sqrt(ss / nb);
  w.ok = true;
}

}  // namespace

WallFit fitWalls(const BinnedReadings& d, const std::vector<BinFit>& f,
                 const std::vector<Line>& start, bool with_b, double fixed_alpha0) {
  WallFit w;
  w.lines = start;
  const bool alpha0_free = !std::isfinite(fixed_alpha0);
  if (!alpha0_free) w.alpha0 = fixed_alpha0;
  for (std::size_t b = 0; b < d.bins.size(); ++b)
    if (d.bins[b].wall >= 0 && f[b].n > 0) w.bins.push_back(b);
  const int nl = static_cast<int>(start.size());
  const int np = 1 + (with_b ? 1 : 0) + 2 * nl;
  const int nb = static_cast<int>(w.bins.size());
  if (nl == 0 || nb < np + 3) return w;
  WallSystem s{Eigen::SparseMatrix<double, Eigen::RowMajor>(nb, np), Eigen::VectorXd(nb),
               Eigen::VectorXd(nb)};
  double tau2 = 1e-6;
  for (int outer = 0; outer < 4; ++outer) {
    if (!wallGaussNewton(d, f, w, WallTerms{with_b, alpha0_free, tau2}, s)) return w;
    tau2 = wallRoughness(f, w, s.r);
  }
  w.tau = std::sqrt(tau2);
  finishWalls(d, f, w, WallTerms{with_b, alpha0_free, tau2}, s);
  return w;
}

}  // namespace lidarcal::diagnosis::static_scene
