// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/tails.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "common/stats_util.hpp"

namespace lidarcal::diagnosis {
namespace {

constexpr double kSqrt2Pi = 2.5066282746310002;
constexpr int kBeta = 1 + kTailCovariates;
/// Smallest k: a broad component narrower than 4 core standard deviations would mimic a smooth
/// noise law (readings at grazing incidence twice as spread) instead of wild readings, and pull
/// the exponents fitted beside it (docs/results/static-diagnosis.md).
constexpr double kMinWide = 4.0;

double logistic(double v) { return 1.0 / (1.0 + std::exp(-v)); }

/// The four weighted densities of a residual: core, broad, mixed, floor.
struct Parts {
  double core = 0.0, wide = 0.0, mix = 0.0, floor = 0.0;
  double total() const { return core + wide + mix + floor; }
};

Parts partsOf(const TailModel& m, const TailBeam& b, double r, double c, double fw, double fd) {
  const double s = std::max(m.sigma(b) * c, 1e-7), ks = std::max(m.broadSigma(b) * c, 1e-7);
  const double pi = m.tailProbability(b);
  const bool can_mix = m.spec.mixed && b.mix_hi > b.mix_lo;
  const double eta = can_mix ? m.mixed : 0.0;
  const double zc = r / s, zw = r / ks;
  Parts p;
  p.core = (1.0 - fw) * (1.0 - eta) * (1.0 - pi) * std::exp(-0.5 * zc * zc) / (s * kSqrt2Pi);
  p.wide = (1.0 - fw) * (1.0 - eta) * pi * std::exp(-0.5 * zw * zw) / (ks * kSqrt2Pi);
  if (can_mix && r >= b.mix_lo && r <= b.mix_hi) p.mix = (1.0 - fw) * eta / (b.mix_hi - b.mix_lo);
  p.floor = fw * fd;
  return p;
}

/// Per-beam sums of the E-step (the M-step needs nothing else).
struct BeamSums {
  double a = 0.0;       ///< sum of core + broad responsibilities
  double t = 0.0;       ///< sum of broad responsibilities
  double s_core = 0.0;  ///< sum of core responsibility * (r / c)^2
  double s_wide = 0.0;  ///< sum of broad responsibility * (r / c)^2
  double mix = 0.0;     ///< sum of mixed responsibilities
  double n = 0.0;       ///< readings
};

/// E-step: per-beam sums and the log-likelihood.
double expectation(const TailModel& m, const std::vector<TailBeam>& beams,
                   const std::vector<TailReading>& readings, double fw, double fd,
                   std::vector<BeamSums>& sums) {
  sums.assign(beams.size(), BeamSums{});
  double ll = 0.0;
  for (const auto& rd : readings) {
    const TailBeam& b = beams[rd.beam];
    const Parts p = partsOf(m, b, rd.residual_m, rd.inflation, fw, fd);
    const double tot = std::max(p.total(), 1e-300);
    ll += std::log(tot);
    const double r2 = std::pow(rd.residual_m / rd.inflation, 2);
    BeamSums& s = sums[rd.beam];
    s.a += (p.core + p.wide) / tot;
    s.t += p.wide / tot;
    s.s_core += p.core / tot * r2;
    s.s_wide += p.wide / tot * r2;
    s.mix += p.mix / tot;
    s.n += 1.0;
  }
  return ll;
}

/// Expected complete log-likelihood of the scales (up to constants), sigma_e at its ML value:
/// core ln s_b = ln sigma_e + kappa l_b + gamma c_b + delta k_b, broad ln s_b + ln k + (rho -
/// kappa)(l_b - l_ref) (l: ln range, c: ln 1/cos phi, k: darkness ln(I_med / I)).
double profileScales(const TailModel& m, const std::vector<TailBeam>& beams,
                     const std::vector<BeamSums>& sums, double* sigma_e) {
  double ss = 0.0, w = 0.0, logh = 0.0;
  for (std::size_t b = 0; b < beams.size(); ++b) {
    if (sums[b].a <= 0.0) continue;
    const double lc =
        m.kappa * beams[b].log_range + m.gamma * beams[b].log_sec_inc + m.delta * beams[b].dark;
    const double lw = lc + std::log(m.wide) +
                      (m.wide_exponent - m.kappa) * (beams[b].log_range - m.ref_log_range);
    ss += sums[b].s_core * std::exp(-2.0 * lc) + sums[b].s_wide * std::exp(-2.0 * lw);
    w += sums[b].a;
    logh += (sums[b].a - sums[b].t) * lc + sums[b].t * lw;
  }
  const double s2 = std::max(ss / std::max(w, 1e-300), 1e-300);
  if (sigma_e) *sigma_e = std::sqrt(s2);
  return -logh - 0.5 * w * std::log(s2);
}

/// One coordinate of the scales by ternary search on the profile (`field` set in a copy).
template <class Set>
void maximiseCoordinate(TailModel& m, const std::vector<TailBeam>& beams,
                        const std::vector<BeamSums>& sums, double lo, double hi, Set set) {
  TailModel t = m;
  const double best = ternaryMax(
      [&](double v) {
        set(t, v);
        return profileScales(t, beams, sums, nullptr);
      },
      lo, hi, 40);
  set(m, best);
}

/// M-step of the noise law and the broad component: exponents (when free), the broad width's
/// ratio k (>= kMinWide at the reference range) and its own range exponent rho, sigma_e.
void maximiseScales(TailModel& m, const std::vector<TailBeam>& beams,
                    const std::vector<BeamSums>& sums) {
  if (m.spec.kappa)
    maximiseCoordinate(m, beams, sums, -1.0, 5.0, [](TailModel& t, double v) { t.kappa = v; });
  if (m.spec.gamma)
    maximiseCoordinate(m, beams, sums, -1.0, 4.0, [](TailModel& t, double v) { t.gamma = v; });
  if (m.spec.delta)
    maximiseCoordinate(m, beams, sums, -1.0, 3.0, [](TailModel& t, double v) { t.delta = v; });
  double tail = 0.0;
  for (const auto& s : sums) tail += s.t;
  if (tail > 1e-6) {
    maximiseCoordinate(m, beams, sums, -1.0, 5.0,
                       [](TailModel& t, double v) { t.wide_exponent = v; });
    maximiseCoordinate(m, beams, sums, std::log(kMinWide), std::log(1e3),
                       [](TailModel& t, double v) { t.wide = std::exp(v); });
  }
  profileScales(m, beams, sums, &m.sigma_e);
}

/// M-step of the logit coefficients: Newton steps on the expected complete log-likelihood of the
/// labels (broad or core), soft labels t_b out of a_b, a small ridge.
void maximiseLogit(TailModel& m, const std::vector<TailBeam>& beams,
                   const std::vector<BeamSums>& sums) {
  using Vec = Eigen::Matrix<double, kBeta, 1>;
  using Mat = Eigen::Matrix<double, kBeta, kBeta>;
  for (int step = 0; step < 3; ++step) {
    Vec g = Vec::Zero();
    Mat h = 1e-3 * Mat::Identity();
    for (std::size_t b = 0; b < beams.size(); ++b) {
      if (sums[b].a <= 0.0) continue;
      Vec x;
      x(0) = 1.0;
      for (int j = 0; j < kTailCovariates; ++j)
        x(1 + j) = m.spec.covariate[static_cast<std::size_t>(j)]
                       ? beams[b].x[static_cast<std::size_t>(j)]
                       : 0.0;
      const double pi = m.tailProbability(beams[b]);
      g += (sums[b].t - sums[b].a * pi) * x;
      h += sums[b].a * pi * (1.0 - pi) * x * x.transpose();
    }
    Vec beta = Eigen::Map<const Vec>(m.beta.data());
    g -= 1e-3 * beta;  // the ridge's gradient
    Vec delta = h.ldlt().solve(g);
    if (!delta.allFinite()) return;
    const double big = delta.cwiseAbs().maxCoeff();
    if (big > 3.0) delta *= 3.0 / big;  // damped: the likelihood may be flat far out
    beta += delta;
    beta(0) = std::clamp(beta(0), -15.0, 5.0);
    for (int j = 0; j < kBeta; ++j) m.beta[static_cast<std::size_t>(j)] = beta(j);
    if (big < 1e-8) return;
  }
}

}  // namespace

const char* tailCovariateName(int k) {
  static const char* names[] = {"edge", "grazing", "range", "dark"};
  return names[k];
}

Effect tailCovariateEffect(int k) {
  static const Effect effects[] = {Effect::mixed_pixels, Effect::incidence_noise,
                                   Effect::range_noise_law, Effect::dark_surface};
  return effects[k];
}

int TailSpec::parameters() const {
  int n = kappa + gamma + mixed + delta;
  for (bool c : covariate) n += c;
  return n;
}

double TailModel::tailProbability(const TailBeam& b) const {
  double v = beta[0];
  for (int j = 0; j < kTailCovariates; ++j)
    if (spec.covariate[static_cast<std::size_t>(j)])
      v += beta[static_cast<std::size_t>(1 + j)] * b.x[static_cast<std::size_t>(j)];
  return logistic(v);
}

double TailModel::sigma(const TailBeam& b) const {
  return sigma_e * std::exp(kappa * b.log_range + gamma * b.log_sec_inc + delta * b.dark);
}

double TailModel::broadSigma(const TailBeam& b) const {
  return sigma(b) * wide * std::exp((wide_exponent - kappa) * (b.log_range - ref_log_range));
}

double TailModel::logDensity(const TailBeam& b, double residual_m, double inflation, double floor_w,
                             double floor_density) const {
  return std::log(
      std::max(partsOf(*this, b, residual_m, inflation, floor_w, floor_density).total(), 1e-300));
}

double TailModel::responsibility(const TailBeam& b, double residual_m, double inflation,
                                 double floor_w, double floor_density) const {
  const Parts p = partsOf(*this, b, residual_m, inflation, floor_w, floor_density);
  return p.wide / std::max(p.total(), 1e-300);
}

namespace {

/// The starting point: a fitted model's parameters (what `spec` holds fixed reset), or the
/// defaults.
TailModel startOf(const TailSpec& spec, double sigma_e_start, const TailModel* start_from) {
  TailModel m;
  if (start_from) {
    m = *start_from;
    m.iterations = 0;
    m.converged = false;
    if (!spec.kappa) m.kappa = 2.0;
    if (!spec.gamma) m.gamma = 0.0;
    if (!spec.delta) m.delta = 0.0;
    if (spec.mixed && !start_from->spec.mixed) m.mixed = 0.05;
    if (!spec.mixed) m.mixed = 0.0;
    for (int j = 0; j < kTailCovariates; ++j)
      if (!spec.covariate[static_cast<std::size_t>(j)])
        m.beta[static_cast<std::size_t>(1 + j)] = 0.0;
  } else {
    m.sigma_e = sigma_e_start > 0.0 ? sigma_e_start : 0.01;
    m.beta[0] = std::log(0.02 / 0.98);
    m.wide = std::max(m.wide, kMinWide);
    m.wide_exponent = m.kappa;
    m.mixed = spec.mixed ? 0.05 : 0.0;
  }
  m.spec = spec;
  return m;
}

}  // namespace

TailModel fitTailModel(const std::vector<TailBeam>& beams, const std::vector<TailReading>& readings,
                       const TailSpec& spec, double sigma_e_start, double floor_w,
                       double floor_density, int max_iterations, const TailModel* start_from) {
  TailModel m = startOf(spec, sigma_e_start, start_from);
  double lr = 0.0, nr = 0.0;
  for (const auto& rd : readings) {
    lr += beams[rd.beam].log_range;
    nr += 1.0;
  }
  m.ref_log_range = nr > 0.0 ? lr / nr : 0.0;
  if (readings.empty()) return m;  // nothing to fit: the start, not converged
  std::vector<BeamSums> sums;
  double prev = -std::numeric_limits<double>::infinity();
  const double n = std::max<double>(static_cast<double>(readings.size()), 1.0);
  for (int it = 0; it < max_iterations; ++it) {
    const double ll = expectation(m, beams, readings, floor_w, floor_density, sums);
    m.iterations = it + 1;
    if (std::abs(ll - prev) < 1e-6 * n) {
      m.converged = true;
      break;
    }
    prev = ll;
    if (spec.mixed) {
      double mix = 0.0, at_edges = 0.0;
      for (std::size_t b = 0; b < beams.size(); ++b)
        if (beams[b].mix_hi > beams[b].mix_lo) {
          mix += sums[b].mix;
          at_edges += sums[b].n;
        }
      m.mixed = at_edges > 0.0 ? std::clamp(mix / at_edges, 1e-4, 0.9) : 0.0;
    }
    maximiseScales(m, beams, sums);
    maximiseLogit(m, beams, sums);
  }
  return m;
}

}  // namespace lidarcal::diagnosis
