// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/landmark_radius.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace lidarcal::detectors {

namespace {

double weightOf(const ArcObservation& a) {
  Eigen::Vector2d m = Eigen::Vector2d::Zero();
  for (const auto& p : a.points) m += p;
  m /= static_cast<double>(a.points.size());
  const double r = std::max(m.norm(), 0.5);  // below 0.5 m the noise no longer shrinks much
  return 1.0 / (r * r * r * r);
}

double totalCost(const std::vector<ArcObservation>& arcs, const std::vector<double>& w,
                 const std::vector<Eigen::Vector2d>& c, double radius) {
  double s = 0.0;
  for (std::size_t k = 0; k < arcs.size(); ++k)
    for (const auto& p : arcs[k].points) {
      const double r = (p - c[k]).norm() - radius;
      s += w[k] * r * r;
    }
  return s;
}

/// The Gauss-Newton normal equations per arc k: A_k (centre block), e_k (centre-radius
/// coupling), b_k, and the radius' own hrr and gradient gr.
struct RadiusNormalEquations {
  std::vector<Eigen::Matrix2d> a;
  std::vector<Eigen::Vector2d> e, b;
  double hrr = 0.0, gr = 0.0;
};

RadiusNormalEquations normalEquations(const std::vector<ArcObservation>& arcs,
                                      const std::vector<double>& w,
                                      const std::vector<Eigen::Vector2d>& c, double radius) {
  RadiusNormalEquations ne;
  auto& a = ne.a;
  auto& e = ne.e;
  auto& b = ne.b;
  a.resize(arcs.size());
  e.resize(arcs.size());
  b.resize(arcs.size());
  for (std::size_t k = 0; k < arcs.size(); ++k) {
    a[k].setZero(), e[k].setZero(), b[k].setZero();
    for (const auto& p : arcs[k].points) {
      const Eigen::Vector2d d = p - c[k];
      const double n = std::max(d.norm(), 1e-300);
      const Eigen::Vector2d jc = -d / n;  // d r / d c_k; d r / d R = -1
      const double r = n - radius;
      a[k] += w[k] * jc * jc.transpose();
      e[k] += -w[k] * jc;
      b[k] += w[k] * jc * r;
      ne.hrr += w[k];
      ne.gr += -w[k] * r;
    }
  }
  return ne;
}

/// The joint fit's state: centres, radius, cost, the Levenberg-Marquardt damping.
struct RadiusFit {
  std::vector<Eigen::Vector2d> c;
  double radius = 0.0, cost = 0.0, lambda = 1e-3;
  bool converged = false;
};

/// One damped step: raises the damping until the cost does not grow (Schur complement: the
/// centres eliminated, the radius step solved, back-substituted). False when none does.
bool levenbergMarquardtStep(const std::vector<ArcObservation>& arcs, const std::vector<double>& w,
                            const RadiusNormalEquations& ne, double radius_min_m,
                            double radius_max_m, RadiusFit& fit) {
  const auto& a = ne.a;
  const auto& e = ne.e;
  const auto& b = ne.b;
  double& lambda = fit.lambda;
  while (lambda < 1e12) {
    double s = ne.hrr * (1.0 + lambda), g = ne.gr;
    std::vector<Eigen::Matrix2d> a_inv(arcs.size());
    for (std::size_t k = 0; k < arcs.size(); ++k) {
      Eigen::Matrix2d ad = a[k];
      ad.diagonal() += lambda * ad.diagonal().cwiseMax(1e-12);
      a_inv[k] = ad.inverse();
      s -= e[k].dot(a_inv[k] * e[k]);
      g -= e[k].dot(a_inv[k] * b[k]);
    }
    const double dr = -g / s;
    std::vector<Eigen::Vector2d> c_new(arcs.size());
    for (std::size_t k = 0; k < arcs.size(); ++k)
      c_new[k] = fit.c[k] - a_inv[k] * (b[k] + e[k] * dr);
    const double r_new = std::clamp(fit.radius + dr, radius_min_m, radius_max_m);
    const double cost_new = totalCost(arcs, w, c_new, r_new);
    if (std::isfinite(cost_new) && cost_new <= fit.cost) {
      const bool negligible = std::abs(r_new - fit.radius) < 1e-10;
      fit.c = std::move(c_new);
      fit.radius = r_new;
      fit.cost = cost_new;
      lambda = std::max(lambda * 0.1, 1e-12);
      fit.converged = negligible;
      return true;
    }
    lambda *= 10.0;
  }
  return false;
}

}  // namespace

RadiusEstimate estimateJointRadius(const std::vector<ArcObservation>& arcs, double radius_min_m,
                                   double radius_max_m, int max_iterations) {
  RadiusEstimate out;
  std::size_t points = 0;
  for (const auto& a : arcs) points += a.points.size();
  if (arcs.empty() || points < 3 + 2 * arcs.size() - 2) {
    out.status = FitStatus::too_few_points;
    return out;
  }
  std::vector<double> w;
  RadiusFit fit;
  double sw = 0.0, wr = 0.0;
  for (const auto& a : arcs) {
    if (a.points.empty()) {
      out.status = FitStatus::too_few_points;
      return out;
    }
    w.push_back(weightOf(a));
    fit.c.emplace_back(a.start.x_m, a.start.y_m);
    sw += w.back();
    wr += w.back() * a.start.radius_m;
  }
  fit.radius = std::clamp(wr / sw, radius_min_m, radius_max_m);
  fit.cost = totalCost(arcs, w, fit.c, fit.radius);
  for (int it = 0; it < max_iterations && !fit.converged; ++it) {
    out.iterations = it + 1;
    const RadiusNormalEquations ne = normalEquations(arcs, w, fit.c, fit.radius);
    if (!levenbergMarquardtStep(arcs, w, ne, radius_min_m, radius_max_m, fit)) break;
  }
  const double radius = fit.radius;
  out.radius_m = radius;
  for (const auto& ck : fit.c) out.centres.push_back(Circle2{ck.x(), ck.y(), radius});
  double wn = 0.0;
  for (std::size_t k = 0; k < arcs.size(); ++k)
    wn += w[k] * static_cast<double>(arcs[k].points.size());
  out.rms_m = std::sqrt(fit.cost / wn);
  out.status = (radius <= radius_min_m || radius >= radius_max_m) ? FitStatus::radius_out_of_limits
                                                                  : FitStatus::ok;
  return out;
}

}  // namespace lidarcal::detectors
