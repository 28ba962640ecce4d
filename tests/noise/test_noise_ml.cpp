// SPDX-License-Identifier: BSD-3-Clause
// Maximum-likelihood noise estimation (variance components in the batch adjustment).

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "common/errors.hpp"
#include "noise/ml.hpp"
#include "noise/noise_scenes.hpp"
#include "noise/problem.hpp"
#include "simulation/observation_sim.hpp"

namespace lidarcal::noise {
namespace {

// Unknowns of the adjustment as one vector: poses 1..K-1, landmarks, biases.
std::vector<double*> unknowns(MlState& st) {
  std::vector<double*> x;
  for (std::size_t k = 1; k < st.poses.size(); ++k) {
    x.push_back(&st.poses[k].x_m);
    x.push_back(&st.poses[k].y_m);
    x.push_back(&st.poses[k].yaw_rad);
  }
  for (auto& l : st.landmarks) x.push_back(&l[0]), x.push_back(&l[1]);
  for (auto& b : st.biases) x.push_back(&b[0]), x.push_back(&b[1]);
  return x;
}

// Jacobian of the residuals (order of residualsAt) w.r.t. the unknowns, by central differences,
// and the weight 1 / variance of each residual's group.
struct DenseModel {
  Eigen::MatrixXd A;
  Eigen::VectorXd w;
  std::vector<int> group;
};

DenseModel denseModel(const NoiseProblem& problem, MlState st,
                      const std::vector<double>& variances) {
  DenseModel d;
  const std::vector<double> r0 = residualsAt(problem, st, &d.group);
  std::vector<double*> x = unknowns(st);
  d.A.resize(static_cast<Eigen::Index>(r0.size()), static_cast<Eigen::Index>(x.size()));
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double keep = *x[j], h = 1e-6;
    *x[j] = keep + h;
    const auto rp = residualsAt(problem, st);
    *x[j] = keep - h;
    const auto rm = residualsAt(problem, st);
    *x[j] = keep;
    for (std::size_t i = 0; i < r0.size(); ++i) d.A(i, j) = (rp[i] - rm[i]) / (2 * h);
  }
  d.w.resize(static_cast<Eigen::Index>(r0.size()));
  for (std::size_t i = 0; i < r0.size(); ++i) d.w[i] = 1.0 / variances[d.group[i]];
  return d;
}

// One lap of the small square: two sensors (one biased), process noise in all three
// components; the dense oracles evaluate at these variances (sensors, then process).
NoiseProblem oneLapProblem(std::uint64_t seed) {
  const ObservationScene scene =
      test::squareScene(1, SensorNoise{0.1, 0.04, 0.02, 0.01}, SensorNoise{0.0, 0.09, 0.0, 0.02},
                        ProcessNoise{0.01, 0.004, 0.001});
  const auto sim = simulation::simulateObservations(scene, seed);
  return makeNoiseProblem(sim.observations, sim.odometry);
}
const std::vector<double> kOneLapVariances{0.04, 0.01, 0.09, 0.02, 0.01, 0.004, 0.001};

TEST(NoiseMlRedundancy, MatchesADenseComputationWithNumericalJacobians) {
  const NoiseProblem problem = oneLapProblem(2);
  const MlState st = initialState(problem);
  const std::vector<double>& variances = kOneLapVariances;

  // Oracle: A by central differences of the residuals, N = A^T W A, r_i = 1 - (A N^-1 A^T W)_ii.
  const DenseModel d = denseModel(problem, st, variances);
  const Eigen::MatrixXd& A = d.A;
  const Eigen::VectorXd& w = d.w;
  const std::vector<int>& group = d.group;
  const Eigen::MatrixXd N = A.transpose() * w.asDiagonal() * A;
  const Eigen::MatrixXd Ninv = N.ldlt().solve(Eigen::MatrixXd::Identity(N.rows(), N.cols()));
  std::vector<double> expected(variances.size(), 0.0);
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    expected[group[i]] += 1.0 - w[i] * A.row(i).dot(Ninv * A.row(i).transpose());

  const std::vector<double> got = groupRedundancy(problem, st, variances, true);
  double total = 0.0;
  for (std::size_t g = 0; g < variances.size(); ++g) {
    SCOPED_TRACE(g);
    EXPECT_NEAR(got[g], expected[g], 1e-4 * std::max(1.0, expected[g]));
    total += got[g];
  }
  // Sum of redundancy numbers = observations - unknowns.
  EXPECT_NEAR(total, static_cast<double>(A.rows()) - static_cast<double>(A.cols()), 1e-6);
}

TEST(NoiseMlInformation, MatchesTheDenseRemlInformationInEveryTermWithAProcessGroup) {
  const NoiseProblem problem = oneLapProblem(3);
  const MlState st = initialState(problem);
  const std::vector<double>& variances = kOneLapVariances;

  // Oracle: the REML information 1/2 tr(P E_g P E_h) with P = W - W A N^-1 A^T W, A by central
  // differences, E_g the selector of group g.
  const DenseModel d = denseModel(problem, st, variances);
  const Eigen::MatrixXd WA = d.w.asDiagonal() * d.A;
  const Eigen::MatrixXd N = d.A.transpose() * WA;
  Eigen::MatrixXd Pm = -WA * N.ldlt().solve(WA.transpose());
  Pm.diagonal() += d.w;
  const Eigen::Index G = 7;
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(G, G);
  for (Eigen::Index i = 0; i < Pm.rows(); ++i)
    for (Eigen::Index j = 0; j < Pm.cols(); ++j)
      expected(d.group[i], d.group[j]) += 0.5 * Pm(i, j) * Pm(i, j);

  const Eigen::MatrixXd got = groupInformation(problem, st, variances, true);
  ASSERT_EQ(got.rows(), G);
  for (Eigen::Index g = 0; g < G; ++g)
    for (Eigen::Index h = 0; h < G; ++h) {
      SCOPED_TRACE(::testing::Message() << g << "," << h);
      if (g >= 4 || h >= 4) {
        // computed in full
        EXPECT_NEAR(got(g, h), expected(g, h), 1e-4 * std::abs(expected(g, h)));
      } else if (g == h) {
        // Correlations between readings are left out: a lower bound, close in this small scene.
        EXPECT_LE(got(g, h), expected(g, h) * (1.0 + 1e-9));
        EXPECT_GE(got(g, h), 0.9 * expected(g, h));
      }
    }
  // What the information is for: the standard errors of the process variances.
  const Eigen::MatrixXd cov_expected = expected.inverse(), cov_got = got.inverse();
  for (Eigen::Index g = 4; g < G; ++g)
    EXPECT_NEAR(std::sqrt(cov_got(g, g)), std::sqrt(cov_expected(g, g)),
                0.02 * std::sqrt(cov_expected(g, g)))
        << g;
}

TEST(NoiseMl, RecoversVariancesAndBiasesWithinFourStandardErrors) {
  // Truth the test controls: two sensors (one biased), process noise in all three components.
  const SensorNoise s0{0.10, 0.04, 0.02, 0.01}, s1{0.0, 0.09, 0.0, 0.02};
  const ProcessNoise q{0.01, 0.004, 0.002};
  const ObservationScene scene = test::squareScene(6, s0, s1, q);
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(seed);
    const auto sim = simulation::simulateObservations(scene, seed);
    const MlNoiseResult r =
        estimateNoiseMl(makeNoiseProblem(sim.observations, sim.odometry), MlNoiseConfig{});
    ASSERT_TRUE(r.converged) << r.message;
    const double truth[] = {s0.range_var_m2,     s0.bearing_var_rad2, s1.range_var_m2,
                            s1.bearing_var_rad2, q.dx_var_m2,         q.dy_var_m2,
                            q.dtheta_var_rad2};
    for (std::size_t g = 0; g < 7; ++g) {
      SCOPED_TRACE(r.groups[g].name);
      // Tolerance: 4 of the estimator's standard errors, sqrt(2 / sum r_ii^2) of the true variance.
      const double se = r.groups[g].standard_error * truth[g] / r.groups[g].variance;
      EXPECT_NEAR(r.groups[g].variance, truth[g], 4.0 * se);
    }
    const double bias[] = {s0.range_mean_m, s0.bearing_mean_rad, s1.range_mean_m,
                           s1.bearing_mean_rad};
    const double est[] = {r.noise.sensors[0].range_mean_m, r.noise.sensors[0].bearing_mean_rad,
                          r.noise.sensors[1].range_mean_m, r.noise.sensors[1].bearing_mean_rad};
    for (std::size_t b = 0; b < 4; ++b)
      EXPECT_NEAR(est[b], bias[b], 4.0 * r.bias_standard_error[b]) << b;
  }
}

TEST(NoiseMl, WithTheProcessNoiseGivenEstimatesTheSensorsAndKeepsTheProcessAsGiven) {
  // Sharma 2020's experiments tell the estimator the true process noise; only the sensors are
  // unknown.
  const SensorNoise s0{0.0, 0.3, 0.0, 0.4}, s1{0.0, 0.5, 0.0, 0.3};  // Sharma 2020 experiment 3
  const ProcessNoise q{0.01, 0.002, 0.001};
  const ObservationScene scene = test::squareScene(4, s0, s1, q);
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    const auto sim = simulation::simulateObservations(scene, seed);
    MlNoiseConfig config;
    config.estimate_process = false;
    config.initial.process = q;  // the sensors start from the default (1), not from the truth
    const MlNoiseResult r =
        estimateNoiseMl(makeNoiseProblem(sim.observations, sim.odometry), config);
    ASSERT_TRUE(r.converged) << r.message;
    const double truth[] = {0.3, 0.4, 0.5, 0.3};
    for (std::size_t g = 0; g < 4; ++g)
      EXPECT_NEAR(r.groups[g].variance, truth[g],
                  4.0 * r.groups[g].standard_error * truth[g] / r.groups[g].variance)
          << r.groups[g].name;
    EXPECT_EQ(r.noise.process.dx_var_m2, q.dx_var_m2);
    EXPECT_EQ(r.noise.process.dy_var_m2, q.dy_var_m2);
    EXPECT_EQ(r.noise.process.dtheta_var_rad2, q.dtheta_var_rad2);
  }
}

TEST(NoiseMl, BeyondTheInformationCapTheStandardErrorsAreDiagonalAndTheEstimateIsUnchanged) {
  const ObservationScene scene =
      test::squareScene(2, SensorNoise{0.0, 0.09, 0.0, 0.02}, SensorNoise{0.0, 0.04, 0.0, 0.01},
                        ProcessNoise{0.01, 0.004, 0.001});
  const auto sim = simulation::simulateObservations(scene, 5);
  const NoiseProblem problem = makeNoiseProblem(sim.observations, sim.odometry);
  const MlNoiseResult full = estimateNoiseMl(problem, MlNoiseConfig{});
  MlNoiseConfig capped;
  capped.max_motions_for_information = problem.stops - 2;  // one motion too many
  const MlNoiseResult diagonal = estimateNoiseMl(problem, capped);
  EXPECT_EQ(full.standard_error_method, "information");
  EXPECT_EQ(diagonal.standard_error_method, "diagonal");
  for (std::size_t g = 0; g < full.groups.size(); ++g) {
    EXPECT_EQ(full.groups[g].variance, diagonal.groups[g].variance) << g;
    EXPECT_GT(full.groups[g].standard_error, 0.0) << g;
  }
}

TEST(NoiseMl, ZeroProcessNoiseIsEstimatedNearZeroAndSensorVariancesStayUnbiased) {
  const SensorNoise s0{0.0, 0.3, 0.0, 0.4}, s1{0.0, 0.5, 0.0, 0.6};  // Sharma 2020 experiment 2
  const ObservationScene scene = test::squareScene(4, s0, s1, ProcessNoise{});
  const auto sim = simulation::simulateObservations(scene, 11);
  const MlNoiseResult r =
      estimateNoiseMl(makeNoiseProblem(sim.observations, sim.odometry), MlNoiseConfig{});
  ASSERT_TRUE(r.converged) << r.message;
  for (int g = 4; g < 7; ++g)
    EXPECT_LT(r.groups[static_cast<std::size_t>(g)].variance, 1e-4)
        << r.groups[static_cast<std::size_t>(g)].name;
  const double truth[] = {0.3, 0.4, 0.5, 0.6};
  for (std::size_t g = 0; g < 4; ++g)
    EXPECT_NEAR(r.groups[g].variance, truth[g],
                4.0 * r.groups[g].standard_error * truth[g] / r.groups[g].variance)
        << g;
}

TEST(NoiseMl, BiasesWithoutTranslationAreADataError) {
  std::vector<OdometryStep> odo{OdometryStep{0, 0, 0, 0}, OdometryStep{1, 0, 0, 0.5}};
  std::vector<Observation> obs{{0, 0, 1, 2.0, 0.1}, {1, 0, 1, 2.0, -0.4}};
  EXPECT_THROW(estimateNoiseMl(makeNoiseProblem(obs, odo), MlNoiseConfig{}), DataError);
}

TEST(NoiseProblem, RejectsStopsOutsideTheOdometryAndSensorGapsAndSkipsUnassociated) {
  std::vector<OdometryStep> odo{OdometryStep{0, 0, 0, 0}, OdometryStep{1, 1, 0, 0}};
  EXPECT_THROW(makeNoiseProblem({{2, 0, 1, 2.0, 0.1}}, odo), InputError);
  EXPECT_THROW(makeNoiseProblem({{0, 1, 1, 2.0, 0.1}}, odo), DataError);  // sensor 0 has nothing
  EXPECT_THROW(makeNoiseProblem({{0, 0, -1, 2.0, 0.1}}, odo), DataError);
  const NoiseProblem p =
      makeNoiseProblem({{1, 0, 7, 2.0, 0.1}, {0, 0, -1, 1.0, 0.0}, {0, 0, 3, 2.0, 0.2}}, odo);
  EXPECT_EQ(p.skipped_unassociated, 1u);
  EXPECT_EQ(p.landmarks, 2);
  ASSERT_EQ(p.observations.size(), 2u);
  EXPECT_EQ(p.observations[0].stop, 0);  // sorted by stop
  EXPECT_EQ(p.landmark_ids[static_cast<std::size_t>(p.observations[0].landmark)], 3);
  EXPECT_EQ(p.stop_begin, (std::vector<std::size_t>{0, 1, 2}));
}

}  // namespace
}  // namespace lidarcal::noise
