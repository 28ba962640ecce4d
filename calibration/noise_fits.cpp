// SPDX-License-Identifier: BSD-3-Clause
#include "calibration/noise_fits.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "calibration/noise_exponent.hpp"
#include "calibration/range_model_fit.hpp"
#include "common/parallel.hpp"

namespace lidarcal::calibration {
namespace {

/// Runs one informational side estimator; a failure (degenerate data) is noted in `failed`, not
/// thrown: the calibration does not depend on it.
template <class Fn>
void sideEstimator(std::map<std::string, std::string>& failed, const char* name, Fn&& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    failed[name] = e.what();
  }
}

}  // namespace

NoiseModel fitNoiseLaw(NoiseKind kind, int order, const BiasPolynomial& f,
                       const std::vector<double>& d, const std::vector<double>& y) {
  NoiseModel n;
  n.kind = kind;
  std::vector<double> r(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) r[i] = y[i] - f(d[i]);
  switch (kind) {
    case NoiseKind::squared: {
      double s = 0.0;
      for (std::size_t i = 0; i < d.size(); ++i) {
        const double fd = f(d[i]);
        s += r[i] * r[i] / (fd * fd * fd * fd);
      }
      n.sigma_e = std::sqrt(s / static_cast<double>(d.size()));
      break;
    }
    case NoiseKind::polynomial:
      n.beta = fitNoisePolynomial(d, r, std::max(order, 0));
      break;
    case NoiseKind::constant: {
      double s = 0.0;
      for (double v : r) s += v * v;
      n.sigma_e = std::sqrt(s / static_cast<double>(r.size()));
      break;
    }
    default:
      throw std::invalid_argument("calibrate: noise law must be squared, polynomial or constant");
  }
  return n;
}

// Two groups: Alhashimi et al. 2021's noise polynomial, and Alhashimi et al. 2016's closed form,
// its ML and the exponent test; each writes only its own fields and failure notes, merged
// afterwards.
void fillNoiseFits(CalibrationModel& m, int order, const std::vector<double>& d,
                   const std::vector<double>& y, const std::vector<std::vector<double>>& batches,
                   int threads) {
  NoiseFits& nf = m.noise_fits;
  nf = NoiseFits{};
  std::vector<double> r(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) r[i] = y[i] - m.model.bias(d[i]);
  const int noise_order = std::max(order, 1), bias_order = std::max(order, 1);
  std::map<std::string, std::string> failed[2];
  parallelFor(2, threadsFor(threads), [&](std::size_t group) {
    if (group == 0) {
      sideEstimator(failed[0], "alhashimi2021_beta",
                    [&] { nf.alhashimi2021_beta = fitNoisePolynomial(d, r, noise_order); });
      return;
    }
    sideEstimator(failed[1], "alhashimi2016_closed_form", [&] {
      const Alhashimi2016Fit cf = fitAlhashimi2016ClosedForm(d, y, bias_order);
      nf.alhashimi2016_cf_alpha = cf.alpha;
      nf.alhashimi2016_cf_sigma_e = cf.sigma_e;
    });
    if (!nf.alhashimi2016_cf_alpha.empty()) {
      sideEstimator(failed[1], "alhashimi2016_ml", [&] {
        const Alhashimi2016Fit ml = fitAlhashimi2016ML(d, y, nf.alhashimi2016_cf_alpha);
        nf.alhashimi2016_ml_alpha = ml.alpha;
        nf.alhashimi2016_ml_sigma_e = ml.sigma_e;
      });
    } else {
      failed[1]["alhashimi2016_ml"] = "starts from the closed form, which could not run";
    }
    sideEstimator(failed[1], "exponent_test", [&] {
      const NoiseExponentTest t = testNoiseExponent(batches);
      nf.exponent_loglik = t.log_likelihood;
      nf.exponent_best = t.best;
      nf.exponent_batches = t.batches;
    });
  });
  for (const auto& f : failed) nf.unavailable.insert(f.begin(), f.end());
}

}  // namespace lidarcal::calibration
