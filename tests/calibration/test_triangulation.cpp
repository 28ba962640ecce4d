// Triangulation (seed 000 section 3.1): exact on noise-free data, equivariant under rigid
// motions, degenerate geometry reported.

#include <cmath>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "calibration/triangulation.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::calibration {
namespace {

simulation::LandmarkLevelConfig noiseFree(const Pose2& start) {
  simulation::LandmarkLevelConfig c;
  c.landmarks = {{1.5, 0.75, 0.12}, {0.3, 2.2, 0.12}, {2.4, 3.4, 0.12}, {3.9, -1.3, 0.12}, {0.9, -2.8, 0.12}};
  c.path.start = start;
  c.path.stops = 10;
  c.path.scans_per_stop = 2;
  c.model.bias.alpha = {0.0525, 0.8838, 0.0584};
  c.model.noise.kind = NoiseKind::none;
  c.model.range_min_m = 0.2;
  c.model.range_max_m = 6.0;
  return c;
}

class TriangulationWeightsTest : public ::testing::TestWithParam<LineWeights> {};

TEST_P(TriangulationWeightsTest, ExactOnNoiseFreeData) {
  const auto cfg = noiseFree(Pose2{});
  const auto sample = simulation::simulateLandmarkLevel(cfg, 1);
  TriangulationConfig tc;
  tc.weights = GetParam();
  const auto est = triangulateAll(sample.obs, tc);
  ASSERT_EQ(est.size(), cfg.landmarks.size());
  for (const auto& e : est) {
    SCOPED_TRACE(e.id);
    ASSERT_TRUE(e.ok()) << e.message;
    EXPECT_NEAR(e.x_m, cfg.landmarks[static_cast<std::size_t>(e.id - 1)].x_m, 1e-9);
    EXPECT_NEAR(e.y_m, cfg.landmarks[static_cast<std::size_t>(e.id - 1)].y_m, 1e-9);
    EXPECT_NEAR(e.residual_rms_m, 0.0, 1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(AllWeights, TriangulationWeightsTest,
                         ::testing::Values(LineWeights::paper, LineWeights::residual, LineWeights::uniform));

TEST(Triangulation, ARigidMotionOfTheSceneMovesTheAnswerTheSameWay) {
  auto cfg = noiseFree(Pose2{});
  cfg.path.sigma_s_m = 0.02;
  cfg.sigma_theta_rad = deg2rad(1.0);
  const Pose2 motion{3.0, -2.0, deg2rad(37.0)};
  auto moved = cfg;
  moved.path.start = motion;
  for (auto& l : moved.landmarks) motion.toWorld(l.x_m, l.y_m, l.x_m, l.y_m);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    // The same seed draws the same noise; in the moved frame it is the same relative noise
    // except the position noise, which is drawn in world axes: compare with sigma_s = 0.
    auto a = cfg, b = moved;
    a.path.sigma_s_m = b.path.sigma_s_m = 0.0;
    const auto ea = triangulateAll(simulation::simulateLandmarkLevel(a, seed).obs, TriangulationConfig{});
    const auto eb = triangulateAll(simulation::simulateLandmarkLevel(b, seed).obs, TriangulationConfig{});
    ASSERT_EQ(ea.size(), eb.size());
    for (std::size_t i = 0; i < ea.size(); ++i) {
      double x = 0, y = 0;
      motion.toWorld(ea[i].x_m, ea[i].y_m, x, y);
      EXPECT_NEAR(eb[i].x_m, x, 1e-9);
      EXPECT_NEAR(eb[i].y_m, y, 1e-9);
    }
  }
}

TEST(Triangulation, CovarianceMatchesTheScatterOverSeeds) {
  auto cfg = noiseFree(Pose2{});
  cfg.sigma_theta_rad = deg2rad(1.0);
  cfg.path.scans_per_stop = 1;
  cfg.path.stops = 20;
  TriangulationConfig tc;
  tc.weights = LineWeights::residual;  // 1 / (d^2 sigma_theta^2): the true variance of each line
  tc.sigma_s_m = 1e-6;
  tc.sigma_theta_rad = deg2rad(1.0);
  const int n = 400;
  double z2 = 0.0;
  int count = 0;
  for (int seed = 1; seed <= n; ++seed) {
    auto c = cfg;
    c.landmarks = {{1.5, 0.75, 0.12}};
    const auto e = triangulateAll(simulation::simulateLandmarkLevel(c, static_cast<std::uint64_t>(seed)).obs, tc)[0];
    const Eigen::Vector2d err(e.x_m - 1.5, e.y_m - 0.75);
    z2 += err.dot(e.covariance.inverse() * err);
    ++count;
  }
  // With the scale estimated from nu = K - 2 residuals, err' C^-1 err is 2 F(2, nu)
  // (Hotelling), of mean 2 nu / (nu - 2) = 2.25 for K = 20; the mean of 400 draws has a
  // standard deviation of about 0.13: allow 4 of them.
  EXPECT_NEAR(z2 / count, 2.0 * 18.0 / 16.0, 0.5);
}

TEST(Triangulation, LandmarkOnThePathLineIsDegenerate) {
  auto cfg = noiseFree(Pose2{});
  cfg.landmarks = {{6.0, 0.001, 0.12}};
  cfg.model.range_max_m = 20.0;
  const auto e = triangulateAll(simulation::simulateLandmarkLevel(cfg, 1).obs, TriangulationConfig{});
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].status, TriangulationStatus::degenerate_geometry);
  EXPECT_NE(e[0].message.find("path line"), std::string::npos);
}

TEST(Triangulation, SeenFromTooFewStops) {
  auto cfg = noiseFree(Pose2{});
  cfg.path.stops = 2;
  const auto e = triangulateAll(simulation::simulateLandmarkLevel(cfg, 1).obs, TriangulationConfig{});
  ASSERT_FALSE(e.empty());
  for (const auto& l : e) EXPECT_EQ(l.status, TriangulationStatus::too_few_stops);
}

}  // namespace
}  // namespace lidarcal::calibration
