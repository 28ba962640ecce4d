#include "calibration/inversion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>
#include <unsupported/Eigen/Polynomials>

namespace lidarcal::calibration {
namespace {

/// Real roots of sum_i c[i] x^i (c may have trailing zeros).
std::vector<double> realRoots(std::vector<double> c) {
  while (c.size() > 1 && c.back() == 0.0) c.pop_back();
  std::vector<double> roots;
  if (c.size() < 2) return roots;
  if (c.size() == 2) {
    roots.push_back(-c[0] / c[1]);
    return roots;
  }
  if (c.size() == 3) {  // numerically stable quadratic formula
    const double a = c[2], b = c[1], q0 = c[0];
    const double disc = b * b - 4.0 * a * q0;
    if (disc < 0.0) return roots;
    const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    if (q != 0.0) roots.push_back(q0 / q);
    roots.push_back(q / a);
    return roots;
  }
  Eigen::VectorXd coeffs(static_cast<Eigen::Index>(c.size()));
  for (std::size_t i = 0; i < c.size(); ++i) coeffs(static_cast<Eigen::Index>(i)) = c[i];
  Eigen::PolynomialSolver<double, Eigen::Dynamic> solver(coeffs);
  for (Eigen::Index i = 0; i < solver.roots().size(); ++i) {
    const auto& z = solver.roots()(i);
    if (std::abs(z.imag()) <= 1e-9 * std::max(1.0, std::abs(z.real()))) {
      roots.push_back(z.real());
    }
  }
  return roots;
}

std::vector<double> polyMul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> out(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

}  // namespace

const char* toString(InversionMethod m) { return m == InversionMethod::ls ? "ls" : "ml"; }

InversionConfig inversionWindow(const RangeModel& model, InversionMethod method) {
  InversionConfig c;
  c.method = method;
  c.d_min_m = 0.0;
  c.d_max_m = 2.0 * std::max(model.range_max_m, 0.1);
  return c;
}

bool isMonotone(const BiasPolynomial& f, double d_min_m, double d_max_m, double* where) {
  // f' is a polynomial: check its sign at its real roots inside the window and at the ends.
  std::vector<double> deriv;
  for (std::size_t i = 1; i < f.alpha.size(); ++i) deriv.push_back(static_cast<double>(i) * f.alpha[i]);
  std::vector<double> probes = {d_min_m, d_max_m};
  for (double r : realRoots(deriv))
    if (r > d_min_m && r < d_max_m) probes.push_back(r);
  std::sort(probes.begin(), probes.end());  // report the first distance where f stops rising
  for (double d : probes)
    if (!(f.derivative(d) > 0.0)) {
      if (where) *where = d;
      return false;
    }
  return true;
}

bool invertsReadingWindow(const BiasPolynomial& f, double y_min_m, double y_max_m, double* where) {
  // Distances whose readings fall in the window: from where f first reaches y_min (or 0) to
  // where it first reaches y_max. f must rise over all of it.
  const double d_end = 4.0 * std::max(y_max_m, 0.1);
  double d_start = 0.0;
  if (f(0.0) < y_min_m) {
    for (double r : realRoots([&] {
           auto c = f.alpha;
           c[0] -= y_min_m;
           return c;
         }()))
      if (r > 0.0 && r < d_end) {
        d_start = d_start == 0.0 ? r : std::min(d_start, r);
      }
  }
  double d_stop = d_end;
  {
    auto c = f.alpha;
    c[0] -= y_max_m;
    for (double r : realRoots(c))
      if (r > d_start && r < d_stop) d_stop = r;
  }
  if (d_stop == d_end && f(d_end) < y_max_m) {
    if (where) *where = d_end;
    return false;
  }
  return isMonotone(f, d_start, d_stop, where);
}

RangeInverter::RangeInverter(const RangeModel& model, const InversionConfig& config) : model_(model), config_(config) {
  if (model_.bias.order() < 1 || (model_.bias.order() == 1 && model_.bias.alpha[1] == 0.0))
    throw std::invalid_argument("RangeInverter: a bias polynomial of order 0 cannot be inverted");
  if (config_.method == InversionMethod::ml && model_.noise.kind != NoiseKind::squared)
    throw std::invalid_argument("RangeInverter: ML inversion (seed 004 eq. 28) needs the squared noise law");
  if (!(config_.d_max_m > config_.d_min_m)) throw std::invalid_argument("RangeInverter: empty distance window");
}

std::optional<double> RangeInverter::invert(double y_m) const {
  if (!std::isfinite(y_m)) return std::nullopt;
  return config_.method == InversionMethod::ls ? invertLs(y_m) : invertMl(y_m);
}

std::optional<double> RangeInverter::invertLs(double y_m) const {
  std::vector<double> c = model_.bias.alpha;  // f(d) - y
  c[0] -= y_m;
  std::optional<double> best;
  for (double r : realRoots(c)) {
    if (r < config_.d_min_m || r > config_.d_max_m) continue;
    if (!best || std::abs(r - y_m) < std::abs(*best - y_m)) best = r;
  }
  return best;
}

std::optional<double> RangeInverter::invertMl(double y_m) const {
  const auto& a = model_.bias.alpha;
  // p(d) = y - f(d); q(d) = y - sum_i (1 - i/2) alpha_i d^i  (eq. 28 with K of eq. 29).
  std::vector<double> p(a.size()), q(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    p[i] = -a[i];
    q[i] = -(1.0 - 0.5 * static_cast<double>(i)) * a[i];
  }
  p[0] += y_m;
  q[0] += y_m;
  std::vector<double> c = polyMul(p, q);
  if (c.size() < 5) c.resize(5, 0.0);
  const double s2 = model_.noise.sigma_e * model_.noise.sigma_e;
  c[4] -= s2;
  // Likelihood of model (21): y ~ N(f(d), sigma_e^2 d^4).
  auto loglik = [&](double d) {
    const double r = y_m - model_.bias(d);
    return -std::log(d * d) - r * r / (2.0 * s2 * d * d * d * d);
  };
  std::optional<double> best;
  for (double r : realRoots(c)) {
    if (r <= 0.0 || r < config_.d_min_m || r > config_.d_max_m) continue;
    if (!best || loglik(r) > loglik(*best)) best = r;
  }
  if (!best || s2 == 0.0) return invertLs(y_m);
  return best;
}

}  // namespace lidarcal::calibration
