// SPDX-License-Identifier: BSD-3-Clause
// Hill climbing (Sharma 2020 ch. 3.4) and the KL noise-consistency objective it climbs.

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.hpp"
#include "noise/hill.hpp"
#include "noise/kl.hpp"
#include "noise/noise_scenes.hpp"
#include "noise/problem.hpp"
#include "simulation/observation_sim.hpp"

namespace lidarcal::noise {
namespace {

TEST(HillClimb, BestObjectiveNeverIncreasesEvenOnANoisyObjective) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    auto noise_rng = makeRng(seed, 7);
    std::normal_distribution<double> noise(0.0, 0.5);
    auto objective = [&](const std::vector<double>& x) {
      return (x[0] - 0.3) * (x[0] - 0.3) + (x[1] + 0.2) * (x[1] + 0.2) + noise(noise_rng);
    };
    HillClimbConfig config;
    config.step = 0.05;
    config.max_evaluations = 300;
    auto rng = makeRng(seed, 0);
    const HillClimbResult r = hillClimb(objective, {1.0, 1.0}, {-10.0, -10.0}, config, rng);
    ASSERT_EQ(static_cast<int>(r.trace.size()), r.evaluations);
    for (std::size_t i = 1; i < r.trace.size(); ++i) {
      EXPECT_LE(r.trace[i].best_value, r.trace[i - 1].best_value) << "evaluation " << i;
      EXPECT_LE(r.trace[i].best_value, r.trace[i].value);
    }
    EXPECT_EQ(r.best_value, r.trace.back().best_value);
    EXPECT_EQ(r.best, r.trace.back().best_params);
  }
}

TEST(HillClimb, FindsTheGridMinimumOfAConvexFunctionAndStopsAfterTheJumps) {
  auto objective = [](const std::vector<double>& x) {
    return 2.0 * (x[0] - 0.42) * (x[0] - 0.42) + (x[1] - 0.17) * (x[1] - 0.17);
  };
  HillClimbConfig config;  // seed's step 0.01 and 5 jumps
  auto rng = makeRng(3, 0);
  const HillClimbResult r = hillClimb(objective, {0.1, 0.9}, {0.0, 0.0}, config, rng);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.best[0], 0.42, 0.005 + 1e-9);
  EXPECT_NEAR(r.best[1], 0.17, 0.005 + 1e-9);
  EXPECT_EQ(r.jumps, config.max_jumps + 0) << "no jump can improve on the global minimum";
}

TEST(HillClimb, RespectsLowerBounds) {
  auto objective = [](const std::vector<double>& x) { return x[0]; };  // wants to go to -infinity
  HillClimbConfig config;
  config.step = 0.1;
  auto rng = makeRng(1, 0);
  const HillClimbResult r = hillClimb(objective, {1.0}, {0.25}, config, rng);
  for (const auto& rec : r.trace) EXPECT_GE(rec.best_params[0], 0.25);
  EXPECT_NEAR(r.best[0], 0.3, 1e-9);
}

class KlObjective : public ::testing::Test {
 protected:
  void SetUp() override {
    const ObservationScene scene =
        test::squareScene(1, SensorNoise{0.0, 0.04, 0.0, 0.01}, SensorNoise{0.0, 0.09, 0.0, 0.02},
                          ProcessNoise{0.01, 0.002, 0.001});
    const auto sim = simulation::simulateObservations(scene, 5);
    problem = makeNoiseProblem(sim.observations, sim.odometry);
    truth = trueNoise(scene);
  }
  NoiseProblem problem;
  NoiseSetting truth;
};

TEST_F(KlObjective, WithCommonRandomNumbersIsADeterministicFunctionOfTheParameters) {
  KlObjectiveConfig config = KlObjectiveConfig::sound();
  config.filter.particles = 20;
  NoiseSetting other = truth;
  other.sensors[0].range_var_m2 *= 1.5;
  const double a1 = evaluateKlObjective(problem, truth, config, 9, 0).total;
  const double b = evaluateKlObjective(problem, other, config, 9, 1).total;
  const double a2 = evaluateKlObjective(problem, truth, config, 9, 2).total;
  EXPECT_EQ(a1, a2);  // same parameters, other evaluation index: same value, bit for bit
  EXPECT_NE(a1, b);
  // The seed's variant draws fresh particle streams per evaluation: the objective is noisy.
  config.common_random_numbers = false;
  const double f1 = evaluateKlObjective(problem, truth, config, 9, 0).total;
  const double f2 = evaluateKlObjective(problem, truth, config, 9, 1).total;
  EXPECT_NE(f1, f2);
}

TEST_F(KlObjective, TermsAreTheClosedFormOfTheAssumedAndPredictedGaussiansInEachVariant) {
  for (const bool faithful : {false, true}) {
    SCOPED_TRACE(faithful);
    KlObjectiveConfig config =
        faithful ? KlObjectiveConfig::faithful() : KlObjectiveConfig::sound();
    config.filter.particles = 10;
    const KlEvaluation e = evaluateKlObjective(problem, truth, config, 3, 0);
    double total = 0.0;
    for (std::size_t s = 0; s < truth.sensors.size(); ++s) {
      const SensorNoise& a = truth.sensors[s];
      // The seed's variant uses the variance value as the standard deviation: N(mean, var^2).
      auto v = [&](double x) { return faithful ? x * x : x; };
      EXPECT_DOUBLE_EQ(e.kl_range[s],
                       gaussianKl(a.range_mean_m, v(a.range_var_m2), e.predicted_range[s].mean,
                                  v(e.predicted_range[s].var)));
      EXPECT_DOUBLE_EQ(e.kl_bearing[s],
                       gaussianKl(a.bearing_mean_rad, v(a.bearing_var_rad2),
                                  e.predicted_bearing[s].mean, v(e.predicted_bearing[s].var)));
      total += e.kl_range[s] + e.kl_bearing[s];
    }
    EXPECT_DOUBLE_EQ(e.total, total);
  }
}

TEST_F(KlObjective, HillClimbingOnItKeepsTheBestObjectiveAndReportsTheBestSetting) {
  KlHillConfig config;
  config.objective.filter.particles = 10;
  config.climb.max_evaluations = 40;
  NoiseSetting start = truth;
  for (auto& s : start.sensors) s.range_var_m2 += 0.05;
  const KlHillResult r = estimateNoiseKlHill(problem, start, config, 4);
  ASSERT_EQ(r.climb.evaluations, 40);
  for (std::size_t i = 1; i < r.climb.trace.size(); ++i)
    EXPECT_LE(r.climb.trace[i].best_value, r.climb.trace[i - 1].best_value);
  // With common random numbers the reported parts add up to the best objective.
  EXPECT_DOUBLE_EQ(r.at_best.total, r.climb.best_value);
  EXPECT_EQ(packNoise(r.noise, config), r.climb.best);
  EXPECT_EQ(r.parameter_names.size(), r.climb.best.size());
}

}  // namespace
}  // namespace lidarcal::noise
