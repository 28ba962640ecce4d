// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/discrepancy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include <Eigen/Dense>

#include "common/stats_util.hpp"
#include "common/student_t.hpp"

namespace lidarcal::calibration {
namespace {

/// Running weighted sums of one entry's readings.
struct EntrySums {
  double w = 0.0, wd = 0.0, wr = 0.0, wrr = 0.0, tape = 0.0;
  std::size_t n = 0;
};

/// Smallest variance an entry is given, square metres: keeps the likelihood finite on
/// noise-free data whose residuals are exactly 0.
constexpr double kVarianceFloorM2 = 1e-20;

/// The largest |distance| of the entries (1 when all are 0).
double distanceScale(const std::vector<EntryResidual>& entries) {
  double scale = 0.0;
  for (const auto& e : entries) scale = std::max(scale, std::abs(e.distance_m));
  return scale > 0.0 ? scale : 1.0;
}

/// Powers 0..order of d / scale.
Eigen::RowVectorXd powersAt(double d, double scale, int order) {
  Eigen::RowVectorXd x(order + 1);
  double p = 1.0;
  for (int i = 0; i <= order; ++i, p *= d / scale) x(i) = p;
  return x;
}

/// The design of the meta-regression: powers of d / scale (scaling changes the restricted
/// likelihood by a constant only, and keeps the powers of order 9 well conditioned).
Eigen::MatrixXd design(const std::vector<EntryResidual>& entries, int order, double scale) {
  Eigen::MatrixXd x(static_cast<Eigen::Index>(entries.size()), order + 1);
  for (std::size_t g = 0; g < entries.size(); ++g)
    x.row(static_cast<Eigen::Index>(g)) = powersAt(entries[g].distance_m, scale, order);
  return x;
}

Eigen::MatrixXd design(const std::vector<EntryResidual>& entries, int order) {
  return design(entries, order, distanceScale(entries));
}

/// V_g = tau^2 + k_g, the entry's whole variance (floored).
double entryVariance(const EntryResidual& e, double tau2) {
  return std::max(tau2 + e.known_variance_m2, kVarianceFloorM2);
}

/// The generalised least squares fit of the entries' residuals on x at tau^2 = tau2, by QR of
/// V^-1/2 X.
struct GlsFit {
  Eigen::VectorXd beta;
  Eigen::MatrixXd r;   ///< the QR's upper triangle R: X' V^-1 X = R' R
  double rss = 0.0;    ///< sum (r_g - x_g' beta)^2 / V_g
  double log_v = 0.0;  ///< sum log V_g
};

GlsFit glsFit(const Eigen::MatrixXd& x, const std::vector<EntryResidual>& entries, double tau2) {
  const Eigen::Index n = x.rows(), p = x.cols();
  Eigen::VectorXd sqrt_w(n), r(n);
  GlsFit out;
  for (Eigen::Index g = 0; g < n; ++g) {
    const double v = entryVariance(entries[static_cast<std::size_t>(g)], tau2);
    out.log_v += std::log(v);
    sqrt_w(g) = 1.0 / std::sqrt(v);
    r(g) = entries[static_cast<std::size_t>(g)].residual_m;
  }
  const Eigen::MatrixXd xw = sqrt_w.asDiagonal() * x;
  const Eigen::VectorXd rw = sqrt_w.asDiagonal() * r;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(xw);
  out.beta = qr.solve(rw);
  out.rss = (rw - xw * out.beta).squaredNorm();
  out.r = qr.matrixQR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  return out;
}

/// -2 x the restricted log-likelihood without its constant, at tau^2 = tau2:
/// sum log V_g + log det(X' V^-1 X) + sum (r_g - x_g' beta_GLS)^2 / V_g.
double restrictedDeviance(const Eigen::MatrixXd& x, const std::vector<EntryResidual>& entries,
                          double tau2) {
  const GlsFit fit = glsFit(x, entries, tau2);
  // log det(X' V^-1 X) = 2 sum log |R_ii|.
  double log_det = 0.0;
  for (Eigen::Index i = 0; i < x.cols(); ++i)
    log_det += 2.0 * std::log(std::max(std::abs(fit.r(i, i)), 1e-300));
  return fit.log_v + log_det + fit.rss;
}

/// The largest tau worth searching: a few times the residuals' spread about the least-squares
/// polynomial (the REML estimate of tau^2 stays below that spread's variance).
double searchLimit(const Eigen::MatrixXd& x, const std::vector<EntryResidual>& entries) {
  Eigen::VectorXd r(x.rows());
  for (Eigen::Index g = 0; g < x.rows(); ++g)
    r(g) = entries[static_cast<std::size_t>(g)].residual_m;
  const Eigen::VectorXd beta = x.householderQr().solve(r);
  const double dof = static_cast<double>(x.rows() - x.cols());
  return 4.0 * std::sqrt(std::max((r - x * beta).squaredNorm() / dof, kVarianceFloorM2));
}

}  // namespace

std::vector<EntryResidual> entryResiduals(const std::vector<double>& d,
                                          const std::vector<double>& y,
                                          const std::vector<double>& weight,
                                          const std::vector<std::size_t>& entry,
                                          const std::vector<double>& tape_sigma,
                                          const BiasPolynomial& f) {
  const std::size_t n = d.size();
  if (y.size() != n || weight.size() != n || entry.size() != n || tape_sigma.size() != n)
    throw std::invalid_argument("entryResiduals: the per-reading vectors differ in length");
  std::map<std::size_t, EntrySums> sums;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(weight[i] > 0.0)) continue;
    EntrySums& s = sums[entry[i]];
    const double r = y[i] - f(d[i]);
    s.w += weight[i];
    s.wd += weight[i] * d[i];
    s.wr += weight[i] * r;
    s.wrr += weight[i] * r * r;
    s.tape = tape_sigma[i];
    ++s.n;
  }
  // The readings' noise pooled over the entries: weighted scatter about each entry's mean, over
  // readings - entries degrees of freedom. The mean of entry g then has variance sigma_w^2 / W_g.
  double within = 0.0;
  std::size_t readings = 0;
  for (const auto& [g, s] : sums) {
    within += std::max(0.0, s.wrr - s.wr * s.wr / s.w);
    readings += s.n;
  }
  const double sigma_w2 =
      readings > sums.size() ? within / static_cast<double>(readings - sums.size()) : 0.0;
  std::vector<EntryResidual> out;
  out.reserve(sums.size());
  for (const auto& [g, s] : sums) {
    EntryResidual e;
    e.entry = g;
    e.distance_m = s.wd / s.w;
    e.residual_m = s.wr / s.w;
    const double tape = f.derivative(e.distance_m) * s.tape;
    e.known_variance_m2 = sigma_w2 / s.w + tape * tape;
    e.tape_sigma_m = s.tape;
    e.weight = s.w;
    e.readings = s.n;
    out.push_back(e);
  }
  return out;
}

double restrictedLogLikelihood(const std::vector<EntryResidual>& entries, int order, double tau_m) {
  return -0.5 * restrictedDeviance(design(entries, order), entries, tau_m * tau_m);
}

Discrepancy estimateDiscrepancy(const std::vector<EntryResidual>& entries, int order) {
  Discrepancy out;
  out.entries = entries.size();
  const int coefficients = order + 1;
  if (order < 0 || static_cast<int>(entries.size()) <= coefficients) {
    out.note =
        "not estimated: " + std::to_string(entries.size()) +
        " measured entries leave no degree of freedom beside " + std::to_string(coefficients) +
        " coefficients, so the intervals are the fitted curve's alone and do not "
        "include how far the sensor may lie from the polynomial between the measured distances";
    return out;
  }
  const Eigen::MatrixXd x = design(entries, order);
  auto loglik = [&](double tau) { return -0.5 * restrictedDeviance(x, entries, tau * tau); };
  // A grid dense near 0 (where the estimate sits for a sensor that follows the polynomial),
  // then the best cell refined: the likelihood need not be unimodal over the whole range.
  const double limit = searchLimit(x, entries);
  constexpr int kGrid = 400;
  auto at = [&](int j) { return limit * std::pow(static_cast<double>(j) / kGrid, 2.0); };
  int best = 0;
  double best_value = loglik(0.0);
  for (int j = 1; j <= kGrid; ++j)
    if (const double v = loglik(at(j)); v > best_value) best_value = v, best = j;
  double tau = at(best);
  if (best > 0) {
    const double refined = ternaryMax(loglik, at(best - 1), at(std::min(best + 1, kGrid)), 100);
    if (loglik(refined) >= best_value) tau = refined;
  }
  double tape2 = 0.0;
  for (const auto& e : entries) tape2 += e.tape_sigma_m * e.tape_sigma_m;
  out.method = "reml";
  out.sigma_m = tau;
  out.dof = static_cast<int>(entries.size()) - coefficients;
  out.tape_sigma_m = std::sqrt(tape2 / static_cast<double>(entries.size()));
  out.note =
      "the predictive interval includes the sensor's scatter about the polynomial between the "
      "measured "
      "distances, beyond their stated tape errors; it does not include an error all of them share "
      "(a tape that "
      "reads long, a wrong pole radius)";
  return out;
}

std::vector<DeletedResidual> deletedResiduals(const std::vector<EntryResidual>& entries,
                                              int order) {
  std::vector<DeletedResidual> out;
  const int coefficients = order + 1;
  if (order < 0 || static_cast<int>(entries.size()) < coefficients + 2) return out;
  const double scale = distanceScale(entries);
  for (std::size_t g = 0; g < entries.size(); ++g) {
    std::vector<EntryResidual> others = entries;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(g));
    const Discrepancy d = estimateDiscrepancy(others, order);
    const double tau2 = d.estimated() ? d.sigma_m * d.sigma_m : 0.0;
    // The others' fit; the prediction's variance x' (X' V^-1 X)^-1 x is |R^-T x|^2.
    const GlsFit fit = glsFit(design(others, order, scale), others, tau2);
    const Eigen::RowVectorXd at = powersAt(entries[g].distance_m, scale, order);
    const Eigen::VectorXd u =
        fit.r.transpose().triangularView<Eigen::Lower>().solve(at.transpose());
    DeletedResidual out_g;
    out_g.entry = entries[g].entry;
    out_g.distance_m = entries[g].distance_m;
    out_g.error_m = entries[g].residual_m - at.dot(fit.beta);
    out_g.se_m = std::sqrt(
        std::max(tau2 + entries[g].known_variance_m2 + u.squaredNorm(), kVarianceFloorM2));
    out_g.dof = static_cast<int>(others.size()) - coefficients;
    out_g.p_value =
        2.0 * studentTCdf(-std::abs(out_g.error_m / out_g.se_m), static_cast<double>(out_g.dof));
    out.push_back(out_g);
  }
  return out;
}

std::map<std::size_t, double> randomEffectsFactors(const std::vector<EntryResidual>& entries,
                                                   const Discrepancy& d) {
  std::map<std::size_t, double> out;
  const bool taped = std::any_of(entries.begin(), entries.end(),
                                 [](const EntryResidual& e) { return e.tape_sigma_m > 0.0; });
  if (!d.estimated() || (d.sigma_m == 0.0 && !taped)) return out;
  const double tau2 = d.sigma_m * d.sigma_m;
  for (const auto& e : entries) out[e.entry] = 1.0 / (e.weight * entryVariance(e, tau2));
  return out;
}

double predictiveStandardError(double curve_se, const Discrepancy& d) {
  if (!d.estimated()) return curve_se;
  return std::sqrt(curve_se * curve_se + d.sigma_m * d.sigma_m);
}

double predictiveFactor(const Discrepancy& d, double level, double known_share) {
  if (!d.estimated() || d.dof <= 0 || known_share >= 1.0) return centralTFactor(level, kInf);
  const double estimated = 1.0 - (known_share > 0.0 ? known_share : 0.0);
  return centralTFactor(level, static_cast<double>(d.dof) / (estimated * estimated));
}

double knownShare(double estimated_variance, double known_variance) {
  const double total = estimated_variance + known_variance;
  return total > 0.0 ? known_variance / total : 0.0;
}

}  // namespace lidarcal::calibration
