// SPDX-License-Identifier: BSD-3-Clause
#include "diagnosis/static_scene/reading_model.hpp"

#include <algorithm>
#include <cmath>

#include "common/pose2.hpp"
#include "common/range_effects.hpp"

namespace lidarcal::diagnosis::static_scene {

FreeTerms freeTermsOf(Effect e) {
  FreeTerms f;
  if (e == Effect::range_noise_law)
    f.kappa = true;
  else if (e == Effect::incidence_noise)
    f.gamma = true;
  else if (e == Effect::range_drift)
    f.drift = true;
  else if (e == Effect::mixed_pixels)
    f.mixed = true;
  else if (e == Effect::heavy_tails)
    f.dof = true;
  else if (e == Effect::quantisation)
    f.quant = true;
  else if (e == Effect::incidence_bias)
    f.wall_b = true;
  else if (e == Effect::dark_surface)
    f.delta = true;
  return f;
}

double shapeOf(const ReadingModel& m, const Bin& b, double loc) {
  return std::pow(std::max(std::abs(loc), 1e-3), m.kappa) *
         incidenceNoiseFactor(m.gamma, b.cos_inc) * darkNoiseFactor(m.delta, b.dark);
}

double centreOf(const ReadingModel& m, const Bin& b, const BinFit& f) {
  return m.robust_edges && b.edge ? f.med : f.m;
}

double expected(const ReadingModel& m, const Bin& b, const BinFit& f, double a, double t) {
  return f.at(a, t) + (centreOf(m, b, f) - f.m);
}

double readingLL(const ReadingModel& m, const BinnedReadings& d, const Bin& b, const BinFit& f,
                 std::size_t i, double floor_weight) {
  const double centre = expected(m, b, f, d.a[i], d.t[i]) + m.drift * (d.t[i] - d.t_mean);
  const double sigma =
      std::max(m.sigma_e * shapeOf(m, b, centre) * std::sqrt(1.0 + 1.0 / std::max(f.n, 1.0)), 1e-6);
  const double y = d.y[i];
  const double z = (y - centre) / sigma;
  double dens;
  if (m.q > 0.0) {
    // Readings rounded to a grid q: the probability of the reading's cell [y - q/2, y + q/2]
    // under the unrounded noise, over q. That is the density of the reading plus a uniform
    // rounding error, so it compares like with like with the other models' densities; the
    // noise scale is the unrounded one (ModelFitter::fitCellScale), so the rounding's
    // variance is not counted twice.
    const double cell = d.y_cell.empty() ? y : d.y_cell[i];
    dens = normalMass(cell - 0.5 * m.q, cell + 0.5 * m.q, centre, sigma) / m.q;
  } else if (m.dof > 0.0) {
    const double nu = m.dof, s = sigma * std::sqrt((nu - 2.0) / nu), x = (y - centre) / s;
    dens = std::exp(std::lgamma(0.5 * (nu + 1.0)) - std::lgamma(0.5 * nu) -
                    0.5 * std::log(nu * kPi) - 0.5 * (nu + 1.0) * std::log1p(x * x / nu)) /
           s;
  } else {
    dens = std::exp(-0.5 * z * z) / (sigma * std::sqrt(2.0 * kPi));
  }
  double mix = 0.0;
  if (m.mixed > 0.0 && b.edge && b.far > b.near && y >= b.near && y <= b.far)
    mix = 1.0 / (b.far - b.near);
  const double window = d.window_max > d.window_min ? 1.0 / (d.window_max - d.window_min) : 0.0;
  const double total =
      (1.0 - floor_weight) * ((1.0 - m.mixed) * dens + m.mixed * mix) + floor_weight * window;
  return std::log(std::max(total, 1e-300));
}

namespace {

/// Fits the free parameters of a reading model on the training scans' readings: the noise law
/// (profile likelihood on per-bin sums), drift, mixed-pixel fraction (EM), Student-t dof.
class ModelFitter {
 public:
  ModelFitter(const BinnedReadings& d, const std::vector<bool>& train, const FreeTerms& fl,
              std::vector<BinFit>& fits);
  ReadingModel fit(double q_detected);

 private:
  const Bin& binOf(std::size_t i) const {
    return binned_.bins[static_cast<std::size_t>(binned_.bin_of[i])];
  }
  const BinFit& fitOf(std::size_t i) const {
    return fits_[static_cast<std::size_t>(binned_.bin_of[i])];
  }
  double residual(std::size_t i) const;
  double sigmaOf(std::size_t i) const {
    return m_.sigma_e * shapeOf(m_, binOf(i), centreOf(m_, binOf(i), fitOf(i)));
  }
  void refresh();
  double profile(const ReadingModel& t, double* sigma_e) const;
  /// profile() with one exponent of the noise law changed.
  template <class Set>
  double profileWith(Set set) const {
    ReadingModel t = m_;
    set(t);
    return profile(t, nullptr);
  }
  void dropOutliers();
  void fitDrift();
  void fitMixed();
  void fitDof();
  void fitCellScale();

  const BinnedReadings& binned_;
  const std::vector<bool>& train_;
  const FreeTerms fl_;
  std::vector<BinFit>& fits_;
  ReadingModel m_;
  std::vector<std::size_t> use_;  // training readings in usable bins
  std::vector<double> weight_;    // 1 - mixed-pixel responsibility
  // The profile likelihood of the noise law works on per-bin sums (the law depends on the bin
  // only): refreshed whenever residuals or weights change.
  std::vector<double> bin_ss_, bin_n_;
};

ModelFitter::ModelFitter(const BinnedReadings& d, const std::vector<bool>& train,
                         const FreeTerms& fl, std::vector<BinFit>& fits)
    : binned_(d),
      train_(train),
      fl_(fl),
      fits_(fits),
      weight_(d.y.size(), 1.0),
      bin_ss_(d.bins.size()),
      bin_n_(d.bins.size()) {}

double ModelFitter::residual(std::size_t i) const {
  return binned_.y[i] - expected(m_, binOf(i), fitOf(i), binned_.a[i], binned_.t[i]) -
         m_.drift * (binned_.t[i] - binned_.t_mean);
}

void ModelFitter::refresh() {
  std::fill(bin_ss_.begin(), bin_ss_.end(), 0.0);
  std::fill(bin_n_.begin(), bin_n_.end(), 0.0);
  for (std::size_t i : use_) {
    if (weight_[i] < 0.5) continue;
    const auto b = static_cast<std::size_t>(binned_.bin_of[i]);
    const double r = residual(i);
    bin_ss_[b] += r * r;
    bin_n_[b] += 1.0;
  }
}

/// Profile log-likelihood of the noise law's exponents (sigma_e at its ML value).
double ModelFitter::profile(const ReadingModel& t, double* sigma_e) const {
  double s2 = 0.0, logh = 0.0, n = 0.0;
  for (std::size_t b = 0; b < binned_.bins.size(); ++b) {
    if (bin_n_[b] == 0.0) continue;
    const double h =
        std::max(shapeOf(t, binned_.bins[b], centreOf(t, binned_.bins[b], fits_[b])), 1e-9);
    s2 += bin_ss_[b] / (h * h);
    logh += bin_n_[b] * std::log(h);
    n += bin_n_[b];
  }
  s2 /= std::max(n, 1.0);
  if (sigma_e) *sigma_e = std::sqrt(s2);
  return -0.5 * n * std::log(std::max(s2, 1e-300)) - logh;
}

/// Outliers beyond 6 sigma do not set the noise scale (they are the floor's business).
void ModelFitter::dropOutliers() {
  for (std::size_t i : use_) {
    const double s = sigmaOf(i);
    if (std::abs(residual(i)) > 6.0 * s)
      weight_[i] = 0.0;
    else if (!fl_.mixed)
      weight_[i] = 1.0;
  }
}

void ModelFitter::fitDrift() {
  double num = 0.0, den = 0.0;
  for (std::size_t i : use_) {
    const double s = sigmaOf(i);
    if (weight_[i] < 0.5) continue;
    const double x = binned_.t[i] - binned_.t_mean;
    num += x * (residual(i) + m_.drift * x) / (s * s);
    den += x * x / (s * s);
  }
  m_.drift = den > 0.0 ? num / den : 0.0;
  fits_ = fitBins(binned_, train_, m_.drift);
  refresh();
  profile(m_, &m_.sigma_e);
}

/// One EM step of the mixed-pixel fraction at edge bins (readings between the two depths).
void ModelFitter::fitMixed() {
  if (m_.mixed <= 0.0) m_.mixed = 0.05;
  double sum = 0.0, n = 0.0;
  for (std::size_t i : use_) {
    const Bin& b = binOf(i);
    if (!b.edge) continue;
    const double s = sigmaOf(i);
    const double z = residual(i) / s;
    const double nd = std::exp(-0.5 * z * z) / (s * std::sqrt(2.0 * kPi));
    const double u = (b.far > b.near && binned_.y[i] >= b.near && binned_.y[i] <= b.far)
                         ? 1.0 / (b.far - b.near)
                         : 0.0;
    const double resp = m_.mixed * u / (m_.mixed * u + (1.0 - m_.mixed) * nd + 1e-300);
    weight_[i] = 1.0 - resp;
    sum += resp;
    n += 1.0;
  }
  m_.mixed = n > 0 ? std::clamp(sum / n, 1e-4, 0.9) : 0.0;
}

void ModelFitter::fitDof() {
  auto ll = [&](double log_nu) {
    ReadingModel t = m_;
    t.dof = 2.0 + std::exp(log_nu);
    double s = 0.0;
    for (std::size_t k = 0; k < use_.size(); k += std::max<std::size_t>(1, use_.size() / 20000)) {
      const std::size_t i = use_[k];
      s += readingLL(t, binned_, binOf(i), fitOf(i), i, 0.0);
    }
    return s;
  };
  m_.dof = 2.0 + std::exp(ternaryMax(ll, std::log(0.1), std::log(300.0), 50));
}

/// sigma_e under the rounded model (readingLL: a normal cell probability per reading): the
/// Gaussian profile's sigma_e holds the rounding's variance too, the cells carry it now. ML over
/// the training readings the noise scale is fitted on (outliers beyond 6 sigma left out), about
/// their bin's location like the profile's (readingLL's widening for a held-out reading is not
/// applied: a training reading is part of its bin's mean).
void ModelFitter::fitCellScale() {
  std::vector<double> shape(use_.size()), centre(use_.size());
  for (std::size_t k = 0; k < use_.size(); ++k) {
    const std::size_t i = use_[k];
    centre[k] = expected(m_, binOf(i), fitOf(i), binned_.a[i], binned_.t[i]) +
                m_.drift * (binned_.t[i] - binned_.t_mean);
    // at the bin's location, as profile() takes it
    shape[k] = shapeOf(m_, binOf(i), centreOf(m_, binOf(i), fitOf(i)));
  }
  auto ll = [&](double log_sigma) {
    const double se = std::exp(log_sigma);
    double s = 0.0;
    for (std::size_t k = 0; k < use_.size(); ++k) {
      const std::size_t i = use_[k];
      if (weight_[i] < 0.5) continue;
      const double sigma = std::max(se * shape[k], 1e-6);
      s += std::log(std::max(
          normalMass(binned_.y[i] - 0.5 * m_.q, binned_.y[i] + 0.5 * m_.q, centre[k], sigma),
          1e-300));
    }
    return s;
  };
  const double top = std::log(std::max(m_.sigma_e, 1e-9));
  m_.sigma_e = std::exp(ternaryMax(ll, top - std::log(1000.0), top + std::log(1.2), 60));
}

ReadingModel ModelFitter::fit(double q_detected) {
  m_.robust_edges = fl_.mixed;
  if (fl_.quant) m_.q = q_detected;
  fits_ = fitBins(binned_, train_, 0.0);
  for (std::size_t i = 0; i < binned_.y.size(); ++i) {
    const int b = binned_.bin_of[i];
    if (b < 0 || fits_[static_cast<std::size_t>(b)].n == 0) continue;
    if (!train_.empty() && !train_[static_cast<std::size_t>(binned_.t[i])]) continue;
    use_.push_back(i);
  }
  for (int pass = 0; pass < 3; ++pass) {
    refresh();
    profile(m_, &m_.sigma_e);
    dropOutliers();
    refresh();
    if (fl_.kappa)
      m_.kappa =
          ternaryMax([&](double k) { return profileWith([k](ReadingModel& t) { t.kappa = k; }); },
                     -1.0, 5.0, 50);
    if (fl_.gamma)
      m_.gamma =
          ternaryMax([&](double g) { return profileWith([g](ReadingModel& t) { t.gamma = g; }); },
                     -1.0, 4.0, 50);
    // The dark-surface exponent as the sequence's joint refinement takes it
    // (JointEffects::dark_noise).
    if (fl_.delta)
      m_.delta =
          ternaryMax([&](double x) { return profileWith([x](ReadingModel& t) { t.delta = x; }); },
                     -1.0, 3.0, 50);
    profile(m_, &m_.sigma_e);
    if (fl_.drift) fitDrift();
    if (fl_.mixed) fitMixed();
  }
  if (fl_.dof) fitDof();
  if (fl_.quant && m_.q > 0.0) fitCellScale();
  return m_;
}

}  // namespace

ReadingModel fitModel(const BinnedReadings& d, const std::vector<bool>& train, const FreeTerms& fl,
                      double q_detected, std::vector<BinFit>& fits) {
  return ModelFitter(d, train, fl, fits).fit(q_detected);
}

}  // namespace lidarcal::diagnosis::static_scene
