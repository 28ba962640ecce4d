#include "diagnosis/stats.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <Eigen/Dense>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "common/pose2.hpp"
#include "common/range_effects.hpp"

namespace lidarcal::diagnosis {

const char* toString(DiagnoseMode mode) { return mode == DiagnoseMode::sequence ? "sequence" : "static"; }

void DiagnoseConfig::validate() const {
  if (replicas < 5) throw std::invalid_argument("DiagnoseConfig: replicas must be >= 5");
  if (folds < 2) throw std::invalid_argument("DiagnoseConfig: folds must be >= 2");
  if (!(alpha > 0.0 && alpha < 1.0)) throw std::invalid_argument("DiagnoseConfig: alpha must be in (0, 1)");
  if (max_order < 1 || max_order > 6) throw std::invalid_argument("DiagnoseConfig: max_order must be 1..6");
  if (!(outlier_floor >= 0.0 && outlier_floor < 0.5)) throw std::invalid_argument("DiagnoseConfig: outlier_floor must be in [0, 0.5)");
  if (!(sigma_s_m > 0.0)) throw std::invalid_argument("DiagnoseConfig: sigma_s_m must be positive");
  if (closeness_replicas < 1) throw std::invalid_argument("DiagnoseConfig: closeness_replicas must be >= 1");
}

double replicaPValue(double value, const std::vector<double>& replicas, bool two_sided, double* effect_size) {
  std::vector<double> r;
  for (double v : replicas)
    if (std::isfinite(v)) r.push_back(v);
  if (effect_size) *effect_size = 0.0;
  if (!std::isfinite(value) || r.size() < 3) return std::numeric_limits<double>::quiet_NaN();
  const double n = static_cast<double>(r.size());
  const double mean = std::accumulate(r.begin(), r.end(), 0.0) / n;
  double var = 0.0;
  for (double v : r) var += (v - mean) * (v - mean);
  const double sd = std::sqrt(var / (n - 1.0));
  if (!(sd > 0.0)) {
    if (effect_size) *effect_size = value == mean ? 0.0 : std::copysign(std::numeric_limits<double>::infinity(), value - mean);
    return value == mean || (!two_sided && value < mean) ? 1.0 : 0.0;
  }
  if (effect_size) *effect_size = (value - mean) / sd;
  const double t = (value - mean) / (sd * std::sqrt(1.0 + 1.0 / n));
  const boost::math::students_t dist(n - 1.0);
  const double upper = boost::math::cdf(boost::math::complement(dist, std::abs(t)));
  if (two_sided) return std::min(1.0, 2.0 * upper);
  return t >= 0.0 ? upper : 1.0 - upper;
}

Discrepancy makeDiscrepancy(std::string name, std::string variable, std::string description, double value,
                            const std::vector<double>& replicas, bool two_sided) {
  Discrepancy d;
  d.name = std::move(name);
  d.variable = std::move(variable);
  d.description = std::move(description);
  d.value = value;
  d.two_sided = two_sided;
  std::vector<double> r;
  for (double v : replicas)
    if (std::isfinite(v)) r.push_back(v);
  if (!r.empty()) {
    d.replica_mean = std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
    double var = 0.0;
    for (double v : r) var += (v - d.replica_mean) * (v - d.replica_mean);
    d.replica_sd = r.size() > 1 ? std::sqrt(var / static_cast<double>(r.size() - 1)) : 0.0;
  }
  d.p_value = replicaPValue(value, replicas, two_sided, &d.effect_size);
  return d;
}

std::vector<Discrepancy> makeBattery(const std::vector<StatisticInfo>& infos, const std::map<std::string, double>& measured,
                                     const std::map<std::string, std::vector<double>>& replicas) {
  std::vector<Discrepancy> out;
  for (const auto& s : infos) {
    const auto it = measured.find(s.name);
    if (it == measured.end()) continue;
    const auto rep = replicas.find(s.name);
    out.push_back(makeDiscrepancy(s.name, s.variable, s.description, it->second,
                                  rep != replicas.end() ? rep->second : std::vector<double>{}, s.two_sided));
  }
  return out;
}

double heldoutPValue(double gain, double se) {
  if (!std::isfinite(gain)) return std::numeric_limits<double>::quiet_NaN();
  if (gain <= 0.0) return 1.0;
  if (!(se > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return 0.5 * std::erfc(gain / se / std::sqrt(2.0));
}

double combinedPValue(double p_heldout, double p_score) {
  return combinedPValue(p_heldout, p_score, std::numeric_limits<double>::quiet_NaN());
}

double combinedPValue(double p_heldout, double p_score, double p_lr) {
  double lowest = std::numeric_limits<double>::infinity();
  int tests = 0;
  for (const double p : {p_heldout, p_score, p_lr})
    if (std::isfinite(p)) {
      lowest = std::min(lowest, p);
      ++tests;
    }
  if (tests == 0) return std::numeric_limits<double>::quiet_NaN();
  return std::min(1.0, tests * lowest);
}

double likelihoodRatioPValue(double statistic, int parameters) {
  if (parameters != 1 || !std::isfinite(statistic)) return std::numeric_limits<double>::quiet_NaN();
  if (statistic <= 0.0) return 1.0;
  return std::erfc(std::sqrt(statistic / 2.0));  // P(chi2_1 > s) = P(|N(0,1)| > sqrt(s))
}

double boundedLikelihoodRatioPValue(double statistic) {
  return statistic > 0.0 ? 0.5 * likelihoodRatioPValue(statistic, 1) : 1.0;
}

std::vector<double> holmAdjust(const std::vector<double>& p) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (std::isfinite(p[i])) idx.push_back(i);
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<double> out(p.size(), std::numeric_limits<double>::quiet_NaN());
  const double m = static_cast<double>(idx.size());
  double running = 0.0;
  for (std::size_t r = 0; r < idx.size(); ++r) {
    running = std::max(running, std::min(1.0, (m - static_cast<double>(r)) * p[idx[r]]));
    out[idx[r]] = running;
  }
  return out;
}

double ksDistance(std::vector<double> a, std::vector<double> b) {
  if (a.empty() || b.empty()) return 0.0;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::size_t i = 0, j = 0;
  double best = 0.0;
  const double na = static_cast<double>(a.size()), nb = static_cast<double>(b.size());
  while (i < a.size() && j < b.size()) {
    const double x = std::min(a[i], b[j]);
    while (i < a.size() && a[i] <= x) ++i;
    while (j < b.size() && b[j] <= x) ++j;
    best = std::max(best, std::abs(static_cast<double>(i) / na - static_cast<double>(j) / nb));
  }
  return best;
}

double cubeRootChi2(double chi2, double dof) {
  if (!(dof > 0.0)) return 0.0;
  return std::cbrt(std::max(chi2, 0.0) / dof);
}

double huberPsi(double z, double c) { return std::clamp(z, -c, c); }

double meanScore(const std::vector<double>& psi, const std::vector<double>& xs) {
  double u = 0.0, info = 0.0;
  for (std::size_t i = 0; i < psi.size() && i < xs.size(); ++i) {
    u += psi[i] * xs[i];
    info += xs[i] * xs[i];
  }
  return info > 0.0 ? u / std::sqrt(info) : 0.0;
}

double spreadScore(const std::vector<double>& z, const std::vector<double>& g) {
  constexpr double kClip = 3.0;
  const std::size_t n = std::min(z.size(), g.size());
  if (n == 0) return 0.0;
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) mean += g[i] / static_cast<double>(n);
  const double c2 = clippedSquareMean(kClip), v2 = clippedSquareVariance(kClip);
  double u = 0.0, info = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double gi = g[i] - mean;
    u += (std::min(z[i] * z[i], kClip * kClip) - c2) * gi;
    info += v2 * gi * gi;
  }
  return info > 0.0 ? u / std::sqrt(info) : 0.0;
}

double clippedSquareMean(double c) {
  // E[min(Z^2, c^2)] = P(|Z| < c) - 2 c phi(c) + c^2 P(|Z| > c).
  const boost::math::normal n;
  const double tail = 2.0 * boost::math::cdf(boost::math::complement(n, c));
  return (1.0 - tail) - 2.0 * c * boost::math::pdf(n, c) + c * c * tail;
}

double clippedSquareVariance(double c) {
  // E[min(Z^4, c^4)] = 3 P(|Z| < c) - 2 phi(c) (c^3 + 3 c) + c^4 P(|Z| > c).
  const boost::math::normal n;
  const double tail = 2.0 * boost::math::cdf(boost::math::complement(n, c));
  const double m4 = 3.0 * (1.0 - tail) - 2.0 * boost::math::pdf(n, c) * (c * c * c + 3.0 * c) + c * c * c * c * tail;
  const double m2 = clippedSquareMean(c);
  return m4 - m2 * m2;
}

std::string nameCause(std::vector<CandidateResult>& cands, double alpha, std::string& decision,
                      const std::vector<std::pair<Effect, Effect>>& nested,
                      const std::vector<std::pair<Effect, Effect>>& indistinguishable) {
  std::vector<double> p;
  for (const auto& c : cands) p.push_back(c.applicable ? c.p_value : std::numeric_limits<double>::quiet_NaN());
  const auto adj = holmAdjust(p);
  for (std::size_t i = 0; i < cands.size(); ++i) {
    cands[i].p_holm = adj[i];
    const double gain = cands[i].heldout_gain_nats_per_point;
    cands[i].significant = cands[i].applicable && std::isfinite(adj[i]) && adj[i] < alpha && gain > 0.0;
  }
  std::vector<std::size_t> sig;
  for (std::size_t i = 0; i < cands.size(); ++i)
    if (cands[i].significant) sig.push_back(i);
  if (sig.empty()) {
    decision = "no candidate is significant (Holm-adjusted p < " + std::to_string(alpha) +
               " with a positive held-out gain): the baseline describes the data";
    return cause::kNone;
  }
  std::size_t top = sig.front();
  for (std::size_t i : sig)
    if (cands[i].heldout_gain_nats_per_point > cands[top].heldout_gain_nats_per_point) top = i;
  decision = std::string("largest held-out gain among the significant effects: ") + toString(cands[top].effect);
  auto close = [&](std::size_t a, std::size_t b) {
    const double se = std::hypot(cands[a].heldout_gain_se, cands[b].heldout_gain_se);
    return cands[b].heldout_gain_nats_per_point >= cands[a].heldout_gain_nats_per_point - 2.0 * se;
  };
  // Parsimony: a significant effect nested in the top one that explains as much.
  std::size_t chosen = top;
  for (std::size_t i : sig)
    for (const auto& [simpler, richer] : nested)
      if (i != top && cands[i].effect == simpler && cands[top].effect == richer && close(top, i)) chosen = i;
  if (chosen != top)
    decision = std::string(toString(cands[chosen].effect)) + " explains as much as " + toString(cands[top].effect) +
               " (held-out gains within two standard errors), which contains it, with fewer parameters";
  if (!cands[chosen].identifiable) {
    decision = std::string(toString(cands[chosen].effect)) + " is significant but cannot be estimated apart from the baseline's parameters (" +
               cands[chosen].note + ")";
    return cause::kNotIdentifiable;
  }
  for (std::size_t i : sig) {
    if (i == chosen || !close(chosen, i)) continue;
    for (const auto& [a, b] : indistinguishable)
      if ((a == cands[i].effect && b == cands[chosen].effect) || (b == cands[i].effect && a == cands[chosen].effect)) {
        decision = std::string(toString(cands[chosen].effect)) + " and " + toString(cands[i].effect) +
                   " are both significant, explain the data equally well and cannot be told apart here";
        return cause::kNotIdentifiable;
      }
  }
  return toString(cands[chosen].effect);
}

DistanceMoments poleDistanceMoments(double along, double perp, const Eigen::Matrix2d& v, double r, double root_extra) {
  // The root's extra share: root_extra r cos(phi), cos(phi) = q / r clamped as the model clamps it.
  const auto extra = [&](double q) { return root_extra == 0.0 ? 0.0 : root_extra * r * clampCosIncidence(q / r); };
  const double sp = std::sqrt(std::max(v(1, 1), 0.0));
  if (std::abs(perp) < r && r - std::abs(perp) > 6.0 * sp) {
    const double q = std::sqrt(r * r - perp * perp);
    const double k = q > 0.05 * r ? 1.0 + root_extra : 1.0;  // the clamped cosine is flat in perp
    const Eigen::Vector2d g(1.0, k * perp / q);  // d(along - q - extra) / d(along, perp)
    return {along - q - extra(q) + 0.5 * k * v(1, 1) * r * r / (q * q * q), g.dot(v * g)};  // the root's curvature in the mean
  }
  if (!(sp > 0.0)) {
    const double q = std::sqrt(std::max(r * r - perp * perp, 0.0));
    return {along - q - extra(q), 0.0};
  }
  double lo = std::max(-r, perp - 8.0 * sp), hi = std::min(r, perp + 8.0 * sp);
  if (!(lo < hi)) {  // far past the tangent: the normal's tail inside, falling at (|perp| - r) / sp^2
    const double width = std::min(2.0 * r, 10.0 * sp * sp / (std::abs(perp) - r));
    lo = perp > 0.0 ? r - width : -r;
    hi = perp > 0.0 ? r : -r + width;
  }
  const double beta = v(0, 1) / v(1, 1), along_var = std::max(v(0, 0) - beta * v(0, 1), 0.0);
  // perp = r sin(t): the root r cos(t) is smooth in t where it is steep in perp (the tangent).
  constexpr std::size_t kPoints = 64;
  const double t0 = std::asin(std::clamp(lo / r, -1.0, 1.0)), t1 = std::asin(std::clamp(hi / r, -1.0, 1.0));
  std::array<double, kPoints> logw{}, d{};
  for (std::size_t k = 0; k < kPoints; ++k) {
    const double t = t0 + (t1 - t0) * (static_cast<double>(k) + 0.5) / static_cast<double>(kPoints);
    const double x = r * std::sin(t), u = (x - perp) / sp, q = r * std::cos(t);
    logw[k] = -0.5 * u * u + std::log(std::cos(t));
    d[k] = along + beta * (x - perp) - q - extra(q);
  }
  const double top = *std::max_element(logw.begin(), logw.end());
  double sw = 0.0, m = 0.0, m2 = 0.0;
  for (std::size_t k = 0; k < kPoints; ++k) {
    const double w = std::exp(logw[k] - top);
    sw += w;
    m += w * d[k];
    m2 += w * d[k] * d[k];
  }
  m /= sw;
  return {m, std::max(m2 / sw - m * m, 0.0) + along_var};
}

double leaveOneOutLogDensity(const Eigen::Vector3d& r, const Eigen::Matrix3d& s) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(Eigen::Matrix3d::Identity() - s);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-9)) return std::numeric_limits<double>::quiet_NaN();
  constexpr double kTwoPi = 6.283185307179586;
  return -0.5 * r.dot(ldlt.solve(r)) + 0.5 * ldlt.vectorD().array().log().sum() - 1.5 * std::log(kTwoPi);
}

std::vector<Eigen::Matrix3d> blockTridiagonalInverseDiagonal(const std::vector<Eigen::Matrix3d>& diagonal,
                                                             const std::vector<Eigen::Matrix3d>& upper,
                                                             std::vector<Eigen::Matrix3d>* upper_out) {
  using Mat3 = Eigen::Matrix3d;
  const std::size_t n = diagonal.size();
  if (n == 0) return {};
  if (upper.size() + 1 < n) throw std::invalid_argument("blockTridiagonalInverseDiagonal: one upper block per pair of neighbours");
  // D_0 = A_0, D_k+1 = A_k+1 - B_k^T D_k^-1 B_k;  C_n-1 = D_n-1^-1,
  // C_k = D_k^-1 + D_k^-1 B_k C_k+1 B_k^T D_k^-1, and C_k,k+1 = -D_k^-1 B_k C_k+1.
  std::vector<Mat3> dinv(n), cov(n);
  Mat3 d = diagonal[0];
  for (std::size_t k = 0; k < n; ++k) {
    dinv[k] = d.inverse();
    if (k + 1 < n) d = diagonal[k + 1] - upper[k].transpose() * dinv[k] * upper[k];
  }
  cov[n - 1] = dinv[n - 1];
  for (std::size_t k = n - 1; k-- > 0;) cov[k] = dinv[k] + dinv[k] * upper[k] * cov[k + 1] * upper[k].transpose() * dinv[k];
  if (upper_out) {
    upper_out->assign(n > 0 ? n - 1 : 0, Mat3::Zero());
    for (std::size_t k = 0; k + 1 < n; ++k) (*upper_out)[k] = -dinv[k] * upper[k] * cov[k + 1];
  }
  return cov;
}

double blockTridiagonalLogDet(const std::vector<Eigen::Matrix3d>& diagonal, const std::vector<Eigen::Matrix3d>& upper) {
  const std::size_t n = diagonal.size();
  if (upper.size() + 1 < n && n > 0) throw std::invalid_argument("blockTridiagonalLogDet: one upper block per pair of neighbours");
  double sum = 0.0;
  Eigen::Matrix3d d = n > 0 ? diagonal[0] : Eigen::Matrix3d::Identity();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::LLT<Eigen::Matrix3d> llt(d);
    if (llt.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
    sum += 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
    if (k + 1 < n) d = diagonal[k + 1] - upper[k].transpose() * llt.solve(upper[k]);
  }
  return sum;
}

}  // namespace lidarcal::diagnosis
