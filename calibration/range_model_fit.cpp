// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/range_model_fit.hpp"

#include "common/information_criteria.hpp"
#include "common/pose2.hpp"
#include "common/stats_util.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <ceres/ceres.h>
#include <Eigen/Dense>

namespace lidarcal::calibration {
namespace {

double evalPoly(const std::vector<double>& c, double x) {
  double v = 0.0;
  for (auto it = c.rbegin(); it != c.rend(); ++it) v = v * x + *it;
  return v;
}

/// Coefficients of p(s) with s = (d - shift) / scale expanded back to powers of d.
std::vector<double> unscale(const Eigen::VectorXd& c, double shift, double scale) {
  const int n = static_cast<int>(c.size());
  std::vector<double> out(static_cast<std::size_t>(n), 0.0);
  // (d - shift)^j / scale^j = sum_m binom(j, m) d^m (-shift)^(j-m) / scale^j
  for (int j = 0; j < n; ++j) {
    double binom = 1.0;
    for (int m = 0; m <= j; ++m) {
      if (m > 0) binom = binom * (j - m + 1) / m;
      out[static_cast<std::size_t>(m)] +=
          c(j) * binom * std::pow(-shift, j - m) / std::pow(scale, j);
    }
  }
  return out;
}

double mse(const std::vector<double>& alpha, const std::vector<RangePair>& pairs, int part) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& p : pairs)
    if (p.part == part) {
      const double r = p.y_m - evalPoly(alpha, p.d_m);
      sum += r * r;
      ++n;
    }
  return n ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

// Profiled negative log-likelihood of Alhashimi et al. 2016 model (1), eqs. 18-20, as a function of
//   alpha: sigma_e^2(alpha) = (1/N) sum (y - f)^2 / f^4, L(alpha) = N/2 ln(2 pi sigma_e^2) + 2 sum
//   ln|f| + N/2.
class Alhashimi2016Profile final : public ceres::FirstOrderFunction {
 public:
  Alhashimi2016Profile(const std::vector<double>& d, const std::vector<double>& y, int params)
      : d_(d), y_(y), params_(params) {}
  int NumParameters() const override { return params_; }
  bool Evaluate(const double* alpha, double* cost, double* gradient) const override {
    const double n = static_cast<double>(d_.size());
    double s = 0.0, logf = 0.0;
    for (std::size_t i = 0; i < d_.size(); ++i) {
      const double f = evalPoly({alpha, alpha + params_}, d_[i]);
      if (!(std::abs(f) > 1e-9)) return false;
      const double r = y_[i] - f;
      s += r * r / (f * f * f * f);
      logf += std::log(std::abs(f));
    }
    s /= n;
    if (!(s > 0.0)) return false;
    *cost = 0.5 * n * (kLog2Pi + std::log(s)) + 2.0 * logf + 0.5 * n;
    if (gradient) {
      std::fill(gradient, gradient + params_, 0.0);
      for (std::size_t i = 0; i < d_.size(); ++i) {
        const double f = evalPoly({alpha, alpha + params_}, d_[i]);
        const double r = y_[i] - f;
        const double f4 = f * f * f * f;
        const double ds_df = (-2.0 * r / f4 - 4.0 * r * r / (f4 * f)) / n;
        const double dl_df = 0.5 * n / s * ds_df + 2.0 / f;
        double dpow = 1.0;
        for (int j = 0; j < params_; ++j, dpow *= d_[i]) gradient[j] += dl_df * dpow;
      }
    }
    return true;
  }

 private:
  const std::vector<double>& d_;
  const std::vector<double>& y_;
  int params_;
};

// Negative log-likelihood of residuals under sigma(d) = |sum beta_i d^i| (Alhashimi et al. 2021 eq.
// 3).
class NoisePolynomialNll final : public ceres::FirstOrderFunction {
 public:
  NoisePolynomialNll(const std::vector<double>& d, const std::vector<double>& r, int params)
      : d_(d), r_(r), params_(params) {}
  int NumParameters() const override { return params_; }
  bool Evaluate(const double* beta, double* cost, double* gradient) const override {
    *cost = 0.0;
    if (gradient) std::fill(gradient, gradient + params_, 0.0);
    for (std::size_t i = 0; i < d_.size(); ++i) {
      const double p = evalPoly({beta, beta + params_}, d_[i]);
      const double sigma = std::abs(p);
      if (!(sigma > 1e-12)) return false;
      *cost += std::log(sigma) + r_[i] * r_[i] / (2.0 * sigma * sigma);
      if (gradient) {
        const double dl_dsigma = 1.0 / sigma - r_[i] * r_[i] / (sigma * sigma * sigma);
        const double sign = p >= 0.0 ? 1.0 : -1.0;
        double dpow = 1.0;
        for (int j = 0; j < params_; ++j, dpow *= d_[i]) gradient[j] += dl_dsigma * sign * dpow;
      }
    }
    return true;
  }

 private:
  const std::vector<double>& d_;
  const std::vector<double>& r_;
  int params_;
};

ceres::GradientProblemSolver::Options lbfgsOptions() {
  ceres::GradientProblemSolver::Options o;
  o.line_search_direction_type = ceres::LBFGS;
  o.max_num_iterations = 500;
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-12;
  o.parameter_tolerance = 1e-12;
  o.logging_type = ceres::SILENT;
  return o;
}

}  // namespace

const char* toString(OrderRule r) { return r == OrderRule::aic ? "aic" : "validation"; }

std::vector<double> fitPolynomial(const std::vector<double>& d, const std::vector<double>& y,
                                  int order, const std::vector<double>& weights) {
  if (order < 0) throw std::invalid_argument("fitPolynomial: negative order");
  if (d.size() != y.size() || (!weights.empty() && weights.size() != d.size()))
    throw std::invalid_argument("fitPolynomial: sizes differ");
  const auto n = static_cast<Eigen::Index>(d.size());
  const int p = order + 1;
  if (n < p) throw std::invalid_argument("fitPolynomial: fewer pairs than coefficients");
  // Centre and scale the distances: the Vandermonde matrix of eq. 26 is badly conditioned
  // in raw powers of d.
  const double mean = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(n);
  double spread = 0.0;
  for (double v : d) spread = std::max(spread, std::abs(v - mean));
  if (!(spread > 0.0)) spread = 1.0;
  Eigen::MatrixXd V(n, p);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double sw = weights.empty() ? 1.0 : std::sqrt(weights[static_cast<std::size_t>(i)]);
    const double s = (d[static_cast<std::size_t>(i)] - mean) / spread;
    double pw = 1.0;
    for (int j = 0; j < p; ++j, pw *= s) V(i, j) = sw * pw;
    rhs(i) = sw * y[static_cast<std::size_t>(i)];
  }
  const Eigen::VectorXd c = V.colPivHouseholderQr().solve(rhs);
  return unscale(c, mean, spread);
}

OrderSelection selectOrder(const std::vector<RangePair>& pairs, int n_max, OrderRule rule,
                           const Admissible& admissible) {
  if (n_max < 0) throw std::invalid_argument("selectOrder: negative n_max");
  std::vector<double> d_all, y_all, d_fit, y_fit;
  for (const auto& p : pairs) {
    d_all.push_back(p.d_m);
    y_all.push_back(p.y_m);
    if (p.part == 0) {
      d_fit.push_back(p.d_m);
      y_fit.push_back(p.y_m);
    }
  }
  OrderSelection sel;
  sel.rule = rule;
  const double n = static_cast<double>(d_all.size());
  double best_aic = std::numeric_limits<double>::infinity(), best_val = best_aic;
  for (int order = 0; order <= n_max; ++order) {
    if (d_all.size() < static_cast<std::size_t>(order + 2)) break;
    OrderFit row;
    row.order = order;
    row.alpha = fitPolynomial(d_all, y_all, order);
    for (std::size_t i = 0; i < d_all.size(); ++i) {
      const double r = y_all[i] - evalPoly(row.alpha, d_all[i]);
      row.rss_m2 += r * r;
    }
    const double k = order + 2.0;  // n + 1 coefficients and the noise variance
    // -log L of Gaussian residuals at the ML variance rss / n
    row.aic = akaike(k, 0.5 * (n * (kLog2Pi + std::log(std::max(row.rss_m2, 1e-300) / n) + 1.0)));
    if (d_fit.size() >= static_cast<std::size_t>(order + 2)) {
      const auto alpha_fit = fitPolynomial(d_fit, y_fit, order);
      row.validation_mse_m2 = mse(alpha_fit, pairs, 1);
      row.test_mse_m2 = mse(alpha_fit, pairs, 2);
    } else {
      row.validation_mse_m2 = row.test_mse_m2 = std::numeric_limits<double>::quiet_NaN();
    }
    row.admissible = !admissible || admissible(row.alpha);
    if (row.admissible && row.aic < best_aic) {
      best_aic = row.aic;
      sel.order_aic = order;
    }
    if (row.admissible && row.validation_mse_m2 < best_val) {
      best_val = row.validation_mse_m2;
      sel.order_validation = order;
    }
    sel.table.push_back(row);
  }
  if (sel.table.empty()) throw std::invalid_argument("selectOrder: too few pairs for any order");
  sel.chosen = rule == OrderRule::aic ? sel.order_aic : sel.order_validation;
  return sel;
}

std::vector<double> fitNoisePolynomial(const std::vector<double>& d,
                                       const std::vector<double>& residuals, int order) {
  std::vector<double> absr(residuals.size());
  for (std::size_t i = 0; i < residuals.size(); ++i)
    absr[i] = std::abs(residuals[i]) * std::sqrt(kPi / 2.0);
  std::vector<double> beta = fitPolynomial(d, absr, order);  // E|r| = sigma sqrt(2/pi)
  // Keep the start positive over the data so |.| is smooth there.
  bool positive = true;
  for (double v : d) positive = positive && evalPoly(beta, v) > 1e-9;
  if (!positive) {
    const double mean =
        std::accumulate(absr.begin(), absr.end(), 0.0) / static_cast<double>(absr.size());
    std::fill(beta.begin(), beta.end(), 0.0);
    beta[0] = std::max(mean, 1e-6);
  }
  ceres::GradientProblem problem(new NoisePolynomialNll(d, residuals, order + 1));
  ceres::GradientProblemSolver::Summary summary;
  ceres::Solve(lbfgsOptions(), problem, beta.data(), &summary);
  return beta;
}

Alhashimi2016Fit fitAlhashimi2016ClosedForm(const std::vector<double>& d,
                                            const std::vector<double>& y, int order) {
  // Eq. 22-24: y/d^2 = sum_i alpha_i d^(i-2) + e. Regress y/d^2 on d^(i-2): the same as
  // weighted least squares of y on d^i with weights 1/d^4 (eq. 25-26).
  std::vector<double> w(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (!(d[i] > 0.0))
      throw std::invalid_argument("fitAlhashimi2016ClosedForm: distances must be positive");
    w[i] = 1.0 / (d[i] * d[i] * d[i] * d[i]);
  }
  Alhashimi2016Fit fit;
  fit.alpha = fitPolynomial(d, y, order, w);
  double s = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double r = (y[i] - evalPoly(fit.alpha, d[i])) / (d[i] * d[i]);
    s += r * r;
  }
  fit.sigma_e = std::sqrt(s / static_cast<double>(d.size()));  // eq. 25
  RangeModel m;
  m.bias.alpha = fit.alpha;
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = fit.sigma_e;
  fit.neg_log_likelihood = negLogLikelihood(m, d, y);
  return fit;
}

Alhashimi2016Fit fitAlhashimi2016ML(const std::vector<double>& d, const std::vector<double>& y,
                                    const std::vector<double>& start) {
  Alhashimi2016Fit fit;
  fit.alpha = start;
  ceres::GradientProblem problem(new Alhashimi2016Profile(d, y, static_cast<int>(start.size())));
  ceres::GradientProblemSolver::Summary summary;
  ceres::Solve(lbfgsOptions(), problem, fit.alpha.data(), &summary);
  fit.iterations = static_cast<int>(summary.iterations.size());
  fit.converged = summary.termination_type == ceres::CONVERGENCE;
  double s = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double f = evalPoly(fit.alpha, d[i]);
    const double r = y[i] - f;
    s += r * r / (f * f * f * f);
  }
  fit.sigma_e = std::sqrt(s / static_cast<double>(d.size()));  // profiled, eq. 19-20
  RangeModel m;
  m.bias.alpha = fit.alpha;
  m.noise.kind = NoiseKind::squared;
  m.noise.sigma_e = fit.sigma_e;
  fit.neg_log_likelihood = negLogLikelihood(m, d, y);
  return fit;
}

double negLogLikelihood(const RangeModel& model, const std::vector<double>& d,
                        const std::vector<double>& y) {
  double nll = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double sigma = model.noise.stddev(d[i], model.bias);
    const double r = y[i] - model.bias(d[i]);
    nll += 0.5 * (kLog2Pi + 2.0 * std::log(sigma) + r * r / (sigma * sigma));
  }
  return nll;
}

}  // namespace lidarcal::calibration
