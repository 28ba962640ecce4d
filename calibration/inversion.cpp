// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/inversion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <vector>

#include "common/stats_util.hpp"

namespace lidarcal::calibration {
namespace {

/// At most kMaxTerms numbers held on the stack: the coefficients of a polynomial (c[i] of x^i)
/// or its roots. The root search per reading allocates nothing.
// degree 18: ML inversion (degree 2n) of order 9, model.json's limit
constexpr std::size_t kMaxTerms = 19;
struct Terms {
  std::array<double, kMaxTerms> v;  // only the first n are set
  std::size_t n = 0;
  void push(double x) { v[n++] = x; }
  double operator[](std::size_t i) const { return v[i]; }
};

Terms termsOf(const std::vector<double>& values) {
  if (values.size() > kMaxTerms)
    throw std::invalid_argument("inversion: polynomials above degree 18 are not supported");
  Terms t;
  for (double x : values) t.push(x);
  return t;
}

std::vector<double> vectorOf(const Terms& t) {
  return std::vector<double>(t.v.begin(), t.v.begin() + static_cast<std::ptrdiff_t>(t.n));
}

/// The polynomial sum_i c[i] x^i without its trailing zero coefficients.
Terms polynomial(const std::vector<double>& c) {
  Terms t = termsOf(c);
  while (t.n > 1 && t.v[t.n - 1] == 0.0) --t.n;
  return t;
}

Terms product(const Terms& a, const Terms& b) {
  Terms out;
  out.n = a.n + b.n - 1;
  if (out.n > kMaxTerms)
    throw std::invalid_argument("inversion: polynomials above degree 18 are not supported");
  std::fill(out.v.begin(), out.v.begin() + static_cast<std::ptrdiff_t>(out.n), 0.0);
  for (std::size_t i = 0; i < a.n; ++i)
    for (std::size_t j = 0; j < b.n; ++j) out.v[i + j] += a[i] * b[j];
  return out;
}

/// c(x) and c'(x) (Horner).
void evaluate(const Terms& c, double x, double& value, double& slope) {
  value = 0.0;
  slope = 0.0;
  for (std::size_t i = c.n; i-- > 0;) {
    slope = slope * x + value;
    value = value * x + c[i];
  }
}

double valueAt(const Terms& c, double x) {
  double value = 0.0, slope = 0.0;
  evaluate(c, x, value, slope);
  return value;
}

Terms derivativeOf(const Terms& c) {
  Terms d;
  for (std::size_t i = 1; i < c.n; ++i) d.push(static_cast<double>(i) * c[i]);
  return d;
}

/// The root of c in [a, b], where c(a) = fa and c(b) = fb have opposite signs and c is
/// monotone: Newton's method from `start` (when inside the bracket) or the secant's root,
/// falling back to bisection whenever a step would leave the bracket.
double bracketedRoot(const Terms& c, double a, double b, double fa, double fb, double start) {
  double x = start > a && start < b ? start : a - fa * (b - a) / (fb - fa);
  if (!(x > a && x < b)) x = 0.5 * (a + b);
  for (int it = 0; it < 200; ++it) {
    double fx = 0.0, dfx = 0.0;
    evaluate(c, x, fx, dfx);
    if (fx == 0.0) return x;
    if ((fx < 0.0) == (fa < 0.0)) {
      a = x;
      fa = fx;
    } else {
      b = x;
    }
    const double newton = dfx != 0.0 ? x - fx / dfx : a - 1.0;
    const double next = newton > a && newton < b ? newton : 0.5 * (a + b);
    const double tolerance =
        2.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(x), 1e-9);
    if (std::abs(next - x) <= tolerance || b - a <= 2.0 * tolerance) return next;
    x = next;
  }
  return x;
}

/// Real roots of c between breaks.front() and breaks.back(), ascending. Between consecutive
/// breaks (the derivative's roots, with the window's ends) c is monotone, so each piece holds
/// at most one root: the pieces whose ends differ in sign are solved by bracketedRoot (from
/// `near` in the piece that holds it). A root where c only touches zero without changing sign
/// is found only where c is exactly 0.
Terms rootsBetween(const Terms& c, const Terms& breaks,
                   double near = std::numeric_limits<double>::quiet_NaN()) {
  Terms roots;
  double a = breaks[0], fa = valueAt(c, a);
  if (fa == 0.0) roots.push(a);
  for (std::size_t k = 1; k < breaks.n; ++k) {
    const double b = breaks[k], fb = valueAt(c, b);
    if (fb == 0.0) {
      if (b > a || roots.n == 0) roots.push(b);
    } else if (fa != 0.0 && (fa < 0.0) != (fb < 0.0)) {
      roots.push(bracketedRoot(c, a, b, fa, fb, near));
    }
    a = b;
    fa = fb;
  }
  return roots;
}

Terms realRoots(const Terms& c, double lo, double hi);

/// lo, the roots of c' inside (lo, hi), and hi: c is monotone between consecutive entries.
Terms monotonePieces(const Terms& c, double lo, double hi) {
  Terms breaks;
  breaks.push(lo);
  const Terms critical = realRoots(derivativeOf(c), lo, hi);
  for (std::size_t k = 0; k < critical.n; ++k)
    if (critical[k] > breaks[breaks.n - 1] && critical[k] < hi) breaks.push(critical[k]);
  breaks.push(hi);
  return breaks;
}

/// Real roots of c in [lo, hi], ascending (c without trailing zero coefficients).
Terms realRoots(const Terms& c, double lo, double hi) {
  if (c.n < 2 || !(hi >= lo)) return {};
  Terms roots;
  if (c.n == 2) {
    const double r = -c[0] / c[1];
    if (r >= lo && r <= hi) roots.push(r);
    return roots;
  }
  if (c.n == 3) {  // the quadratic formula in its cancellation-free form
    const double disc = c[1] * c[1] - 4.0 * c[2] * c[0];
    if (disc < 0.0) return roots;
    const double q = -0.5 * (c[1] + std::copysign(std::sqrt(disc), c[1]));
    double r1 = q / c[2], r2 = q != 0.0 ? c[0] / q : r1;
    if (r2 < r1) std::swap(r1, r2);
    if (r1 >= lo && r1 <= hi) roots.push(r1);
    if (r2 > r1 && r2 >= lo && r2 <= hi) roots.push(r2);
    return roots;
  }
  return rootsBetween(c, monotonePieces(c, lo, hi));
}

std::vector<double> realRoots(const std::vector<double>& c, double lo, double hi) {
  return vectorOf(realRoots(polynomial(c), lo, hi));
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
  std::vector<double> probes = {d_min_m, d_max_m};
  for (double r : vectorOf(realRoots(derivativeOf(polynomial(f.alpha)), d_min_m, d_max_m)))
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
    for (double r : realRoots(
             [&] {
               auto c = f.alpha;
               c[0] -= y_min_m;
               return c;
             }(),
             0.0, d_end))
      if (r > 0.0 && r < d_end) {
        d_start = d_start == 0.0 ? r : std::min(d_start, r);
      }
  }
  double d_stop = d_end;
  {
    auto c = f.alpha;
    c[0] -= y_max_m;
    for (double r : realRoots(c, d_start, d_stop))
      if (r > d_start && r < d_stop) d_stop = r;
  }
  if (d_stop == d_end && f(d_end) < y_max_m) {
    if (where) *where = d_end;
    return false;
  }
  return isMonotone(f, d_start, d_stop, where);
}

RangeInverter::RangeInverter(const RangeModel& model, const InversionConfig& config)
    : model_(model), config_(config) {
  if (model_.bias.order() < 1 || (model_.bias.order() == 1 && model_.bias.alpha[1] == 0.0))
    throw std::invalid_argument("RangeInverter: a bias polynomial of order 0 cannot be inverted");
  if (config_.method == InversionMethod::ml && model_.noise.kind != NoiseKind::squared)
    throw std::invalid_argument(
        "RangeInverter: ML inversion (Alhashimi et al. 2016 eq. 28) needs the squared noise law");
  if (!(config_.d_max_m > config_.d_min_m))
    throw std::invalid_argument("RangeInverter: empty distance window");
  if (model_.bias.alpha.size() > 10)
    throw std::invalid_argument("RangeInverter: bias polynomials above order 9 are not supported");
  ls_pieces_ =
      vectorOf(monotonePieces(polynomial(model_.bias.alpha), config_.d_min_m, config_.d_max_m));
}

std::optional<double> RangeInverter::invert(double y_m) const {
  if (!std::isfinite(y_m)) return std::nullopt;
  return config_.method == InversionMethod::ls ? invertLs(y_m) : invertMl(y_m);
}

std::optional<double> RangeInverter::invertLs(double y_m) const {
  Terms c = polynomial(model_.bias.alpha);  // f(d) - y
  c.v[0] -= y_m;
  const Terms roots = rootsBetween(c, termsOf(ls_pieces_));
  std::optional<double> best;
  for (std::size_t k = 0; k < roots.n; ++k)
    if (!best || std::abs(roots[k] - y_m) < std::abs(*best - y_m)) best = roots[k];
  return best;
}

std::optional<double> RangeInverter::invertMl(double y_m) const {
  const auto& a = model_.bias.alpha;
  // p(d) = y - f(d); q(d) = y - sum_i (1 - i/2) alpha_i d^i  (eq. 28 with K of eq. 29).
  Terms p, q;
  for (std::size_t i = 0; i < a.size(); ++i) {
    p.push(-a[i]);
    q.push(-(1.0 - 0.5 * static_cast<double>(i)) * a[i]);
  }
  p.v[0] += y_m;
  q.v[0] += y_m;
  Terms c = product(p, q);
  while (c.n < 5) c.push(0.0);
  const double s2 = model_.noise.sigma_e * model_.noise.sigma_e;
  c.v[4] -= s2;
  while (c.n > 1 && c.v[c.n - 1] == 0.0) --c.n;
  // Likelihood of model (21): y ~ N(f(d), sigma_e^2 d^4).
  auto loglik = [&](double d) {
    const double r = y_m - model_.bias(d);
    return -std::log(d * d) - r * r / (2.0 * s2 * d * d * d * d);
  };
  // The stationary points lie on the pieces between the roots of c'. The piece holding the LS
  // distance (y = f(d)) is solved first, from that distance: its stationary point is usually the
  // most likely. Since the likelihood is at most -ln d^2, a piece starting at a cannot beat a
  // best likelihood above -ln a^2 and is not searched.
  const std::optional<double> ls = invertLs(y_m);
  const Terms breaks = monotonePieces(c, std::max(config_.d_min_m, 0.0), config_.d_max_m);
  std::optional<double> best;
  auto searchPiece = [&](std::size_t k, double start) {
    Terms piece;
    piece.push(breaks[k]);
    piece.push(breaks[k + 1]);
    const Terms roots = rootsBetween(c, piece, start);
    for (std::size_t i = 0; i < roots.n; ++i)
      if (roots[i] > 0.0 && (!best || loglik(roots[i]) > loglik(*best))) best = roots[i];
  };
  std::size_t first = breaks.n;
  for (std::size_t k = 0; ls && k + 1 < breaks.n; ++k)
    if (breaks[k] <= *ls && *ls <= breaks[k + 1]) first = k;
  if (first < breaks.n) searchPiece(first, *ls);
  for (std::size_t k = 0; k + 1 < breaks.n; ++k) {
    if (k == first || (best && breaks[k] > 0.0 && -std::log(breaks[k] * breaks[k]) < loglik(*best)))
      continue;
    searchPiece(k, std::numeric_limits<double>::quiet_NaN());
  }
  if (!best || s2 == 0.0) return ls;
  return best;
}

double correctionStandardError(const BiasPolynomial& f, const std::vector<double>& covariance,
                               double d, double d_min, double d_max) {
  const std::size_t n = f.alpha.size();
  if (covariance.size() != n * n || n == 0) return kNaN;
  const double e = std::clamp(d, d_min, d_max);
  // g_i = d/d alpha_i of f(e) + f'(e) (d - e) = e^i + i e^(i-1) (d - e).
  std::vector<double> g(n);
  double power = 1.0, lower = 0.0;  // e^i and e^(i-1)
  for (std::size_t i = 0; i < n; ++i) {
    g[i] = power + static_cast<double>(i) * lower * (d - e);
    lower = power;
    power *= e;
  }
  double v = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) v += g[i] * covariance[i * n + j] * g[j];
  const double slope = f.derivative(e);
  return v >= 0.0 && slope > 0.0 ? std::sqrt(v) / slope : kNaN;
}

namespace {

/// The distance beyond `edge` at which f reaches y: Newton's method from the tangent at the
/// edge; the tangent's answer when f turns over on the way (f' <= 0) or does not converge.
double distanceBeyondEdge(const BiasPolynomial& f, double edge, double y) {
  const double slope = f.derivative(edge);
  if (!(slope > 0.0)) return edge;
  const double tangent = edge + (y - f(edge)) / slope;
  double d = tangent;
  for (int i = 0; i < 30; ++i) {
    const double s = f.derivative(d);
    if (!(s > 0.0)) return tangent;
    const double step = (f(d) - y) / s;
    d -= step;
    if (std::abs(step) <= 1e-12 * std::max(1.0, std::abs(d))) return d;
  }
  return tangent;
}

}  // namespace

std::pair<double, double> fittedRange(const std::vector<double>& d, const std::vector<double>& y,
                                      const BiasPolynomial& f) {
  double lo = *std::min_element(d.begin(), d.end()), hi = *std::max_element(d.begin(), d.end());
  const auto [y_lo, y_hi] = std::minmax_element(y.begin(), y.end());
  // The nearest and farthest targets' readings scatter a few noise widths beyond f(lo) and f(hi).
  if (*y_lo < f(lo)) lo = std::clamp(distanceBeyondEdge(f, lo, *y_lo), 0.0, lo);
  if (*y_hi > f(hi)) hi = std::max(hi, distanceBeyondEdge(f, hi, *y_hi));
  return {lo, hi};
}

}  // namespace lidarcal::calibration
