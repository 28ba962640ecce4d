// SPDX-License-Identifier: BSD-3-Clause
// The tail model (diagnosis/tails.hpp): EM recovers a contamination model from its own draws and
// stays finite on degenerate inputs.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/tails.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

/// Residuals drawn from the tail model itself: the EM recovers its parameters (oracle: the truth).
TEST(DiagnoseTails, EmRecoversTheContaminationModelFromItsOwnDraws) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    auto rng = makeRng(seed, 17);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    TailModel truth;
    truth.sigma_e = 0.002;
    truth.gamma = 1.0;
    truth.wide = 8.0;
    truth.beta = {-4.0, 3.0, 0.0, 0.0, 0.0};
    truth.spec.covariate[kTailEdge] = true;
    std::vector<TailBeam> beams(200);
    std::vector<TailReading> readings;
    for (std::size_t b = 0; b < beams.size(); ++b) {
      beams[b].log_range = std::log(1.0 + 3.0 * unit(rng));
      beams[b].log_sec_inc = -std::log(std::cos(deg2rad(70.0) * unit(rng)));
      beams[b].x = {b % 2 == 0 ? 1.0 : 0.0, beams[b].log_sec_inc, beams[b].log_range - 0.8, 0.0};
      for (int k = 0; k < 200; ++k) {
        const double s = truth.sigma(beams[b]) *
                         (unit(rng) < truth.tailProbability(beams[b]) ? truth.wide : 1.0);
        readings.push_back({b, s * normal(rng), 1.0});
      }
    }
    TailSpec spec;
    spec.covariate = {true, true, true, false};
    spec.gamma = true;
    const TailModel m = fitTailModel(beams, readings, spec, 0.01, 1e-3, 1.0 / 12.0);
    EXPECT_TRUE(m.converged);
    EXPECT_NEAR(m.sigma_e, 0.002, 0.0001);
    EXPECT_NEAR(m.gamma, 1.0, 0.05);
    EXPECT_NEAR(m.wide, 8.0, 0.5);
    EXPECT_NEAR(m.beta[0], -4.0, 0.3);
    EXPECT_NEAR(m.beta[1 + kTailEdge], 3.0, 0.3);
    EXPECT_NEAR(m.beta[1 + kTailGrazing], 0.0, 0.3);  // covariates without effect stay near 0
    EXPECT_NEAR(m.beta[1 + kTailRange], 0.0, 0.3);
  }
}

/// Degenerate inputs: no readings, or every residual zero (a sensor that repeats itself): finite
/// parameters, no crash; no readings is reported as not converged.
TEST(DiagnoseTails, DegenerateInputsGiveFiniteParameters) {
  std::vector<TailBeam> beams(3);
  TailSpec spec;
  spec.covariate = {true, true, true, true};
  spec.kappa = spec.gamma = spec.mixed = true;
  const TailModel none = fitTailModel(beams, {}, spec, 0.01, 1e-3, 0.1);
  EXPECT_FALSE(none.converged);
  std::vector<TailReading> zeros;
  for (std::size_t b = 0; b < beams.size(); ++b)
    for (int k = 0; k < 20; ++k) zeros.push_back({b, 0.0, 1.0});
  const TailModel flat = fitTailModel(beams, zeros, spec, 0.01, 1e-3, 0.1);
  for (double v : {flat.sigma_e, flat.kappa, flat.gamma, flat.wide, flat.mixed, flat.beta[0]})
    EXPECT_TRUE(std::isfinite(v));
  EXPECT_TRUE(std::isfinite(flat.logDensity(beams[0], 0.001, 1.0, 1e-3, 0.1)));
}

}  // namespace
}  // namespace lidarcal::diagnosis
