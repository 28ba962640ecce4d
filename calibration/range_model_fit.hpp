// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The range model from (distance, reading) pairs: Alhashimi et al. 2021 section 3.2 (polynomial
// bias by linear least squares, eqs. 26-28; order by AIC or held-out validation) and Alhashimi et
// al. 2016 section 5 (noise sigma_e f(d)^2: closed-form approximation eqs. 21-26, full ML eqs.
// 18-20).

#include <functional>
#include <string>
#include <vector>

#include "common/range_model.hpp"

namespace lidarcal::calibration {

/// One reading with its (estimated or true) distance.
struct RangePair {
  double d_m = 0.0;  ///< distance the reading should have been (estimated from landmarks, or true)
  double y_m = 0.0;  ///< raw reading
  /// split for order selection: 0 fit, 1 choose, 2 test (Alhashimi et al. 2021 section 4.3)
  int part = 0;
};

/// Least-squares polynomial y = sum_i alpha_i d^i of a given order (eq. 28), solved by QR in
/// double precision on centred and scaled distances. Optional weights (WLS).
std::vector<double> fitPolynomial(const std::vector<double>& d, const std::vector<double>& y,
                                  int order, const std::vector<double>& weights = {});

/// How the order is chosen.
enum class OrderRule { aic, validation };
const char* toString(OrderRule r);

struct OrderFit {
  int order = 0;                   ///< polynomial order n
  std::vector<double> alpha;       ///< alpha_0..alpha_n fitted on all pairs
  double rss_m2 = 0.0;             ///< residual sum of squares on all pairs
  double aic = 0.0;                ///< 2k + N (ln(2 pi RSS/N) + 1), k = n + 2 (eq. 4, Gaussian)
  double validation_mse_m2 = 0.0;  ///< fitted on part 0, mean squared error on part 1
  double test_mse_m2 = 0.0;        ///< fitted on part 0, mean squared error on part 2
  bool admissible = true;          ///< passes the caller's test (e.g. invertible over the readings)
};

struct OrderSelection {
  std::vector<OrderFit> table;  ///< one row per order 0..n_max
  int order_aic = 0;            ///< smallest AIC
  int order_validation = 0;     ///< smallest validation MSE
  int chosen = 0;               ///< per the rule
  OrderRule rule = OrderRule::aic;
};

/// Whether a fitted polynomial may be chosen (e.g. it must be invertible over the readings).
using Admissible = std::function<bool(const std::vector<double>& alpha)>;

/// Fits orders 0..n_max and selects one among the admissible (all, when no test is given).
OrderSelection selectOrder(const std::vector<RangePair>& pairs, int n_max, OrderRule rule,
                           const Admissible& admissible = {});

/// Alhashimi et al. 2021's noise form: sigma(d) = |sum_i beta_i d^i| fitted by maximum likelihood
/// to residuals r_i = y_i - f(d_i) (Ceres, started from a least-squares fit of |r| sqrt(pi/2)).
std::vector<double> fitNoisePolynomial(const std::vector<double>& d,
                                       const std::vector<double>& residuals, int order);

/// Alhashimi et al. 2016 eqs. 21-26: alpha and sigma_e^2 of y = f(d) + d^2 e in closed form
/// (regression of y/d^2 on d^(i-2)).
struct Alhashimi2016Fit {
  std::vector<double> alpha;  ///< alpha_0..alpha_n
  double sigma_e = 0.0;       ///< noise scale, m^-1
  /// of model (1) y = f(d) + f(d)^2 e at these parameters (eq. 18 / 2 + const)
  double neg_log_likelihood = 0.0;
  int iterations = 0;  ///< optimiser iterations (0 for the closed form)
  bool converged = true;
};
Alhashimi2016Fit fitAlhashimi2016ClosedForm(const std::vector<double>& d,
                                            const std::vector<double>& y, int order);

/// Alhashimi et al. 2016 eqs. 18-20: full maximum likelihood of y = f(d) + f(d)^2 e over (alpha,
/// sigma_e), sigma_e profiled out, alpha by L-BFGS (Ceres) from `start` (e.g. the closed form).
Alhashimi2016Fit fitAlhashimi2016ML(const std::vector<double>& d, const std::vector<double>& y,
                                    const std::vector<double>& start);

/// Negative log-likelihood (with constants) of readings y at distances d under a range model.
double negLogLikelihood(const RangeModel& model, const std::vector<double>& d,
                        const std::vector<double>& y);

}  // namespace lidarcal::calibration
