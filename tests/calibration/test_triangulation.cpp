// SPDX-License-Identifier: BSD-3-Clause
// Triangulation (Alhashimi et al. 2021 section 3.1): exact on noise-free data, equivariant under
// rigid motions, the eq. 25 weights on noisy data against a hand-built weighted least squares,
// degenerate geometry reported.

#include <cmath>
#include <map>

#include <gtest/gtest.h>
#include <Eigen/LU>
#include <Eigen/QR>

#include "calibration/triangulation.hpp"
#include "simulation/landmark_level.hpp"

namespace lidarcal::calibration {
namespace {

simulation::LandmarkLevelConfig noiseFree(const Pose2& start) {
  simulation::LandmarkLevelConfig c;
  c.landmarks = {
      {1.5, 0.75, 0.12}, {0.3, 2.2, 0.12}, {2.4, 3.4, 0.12}, {3.9, -1.3, 0.12}, {0.9, -2.8, 0.12}};
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
                         ::testing::Values(LineWeights::paper, LineWeights::residual,
                                           LineWeights::uniform));

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
    const auto ea =
        triangulateAll(simulation::simulateLandmarkLevel(a, seed).obs, TriangulationConfig{});
    const auto eb =
        triangulateAll(simulation::simulateLandmarkLevel(b, seed).obs, TriangulationConfig{});
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
    const auto e = triangulateAll(
        simulation::simulateLandmarkLevel(c, static_cast<std::uint64_t>(seed)).obs, tc)[0];
    const Eigen::Vector2d err(e.x_m - 1.5, e.y_m - 0.75);
    z2 += err.dot(e.covariance.inverse() * err);
    ++count;
  }
  // With the scale estimated from nu = K - 2 residuals, err' C^-1 err is 2 F(2, nu)
  // (Hotelling), of mean 2 nu / (nu - 2) = 2.25 for K = 20; the mean of 400 draws has a
  // standard deviation of about 0.13: allow 4 of them.
  EXPECT_NEAR(z2 / count, 2.0 * 18.0 / 16.0, 0.5);
}

TEST(Triangulation, ThreeNoisyBearingsLocateTheLandmarkWithinTheirReportedUncertainty) {
  // Three stops, one scan each: every bearing line counts. Three noisy lines do not meet in one
  // point, so the residual and the covariance are not zero, and the error stays within the
  // reported uncertainty as often as Hotelling's distribution says: err' C^-1 err is 2 F(2, 1)
  // (scale from K - 2 = 1 residual degree of freedom), below 2 x 199.5 in 95 % of the draws
  // (F(2, nu) quantile nu/2 ((1 - p)^(-2/nu) - 1)).
  auto cfg = noiseFree(Pose2{});
  cfg.sigma_theta_rad = deg2rad(1.0);
  cfg.path.scans_per_stop = 1;
  cfg.path.stops = 3;
  cfg.path.step_m = 0.5;
  TriangulationConfig tc;
  tc.weights = LineWeights::residual;
  tc.sigma_s_m = 1e-6;
  tc.sigma_theta_rad = deg2rad(1.0);
  const int n = 400;
  int covered = 0;
  for (int seed = 1; seed <= n; ++seed) {
    auto c = cfg;
    c.landmarks = {{1.0, 1.5, 0.12}};
    const auto e = triangulateAll(
        simulation::simulateLandmarkLevel(c, static_cast<std::uint64_t>(seed)).obs, tc)[0];
    ASSERT_EQ(e.status, TriangulationStatus::ok) << seed;
    ASSERT_EQ(e.stops, 3);
    ASSERT_GT(e.residual_rms_m, 0.0) << seed;
    ASSERT_GT(e.covariance.determinant(), 0.0) << seed;
    const Eigen::Vector2d err(e.x_m - 1.0, e.y_m - 1.5);
    covered += err.dot(e.covariance.inverse() * err) <= 2.0 * 199.5;
  }
  // 95 % of 400: 380, binomial sd 4.4; allow three of them.
  EXPECT_NEAR(covered, 380, 13);
}

/// Eq. 23 with the eq. 25 weights built here from the raw sightings, by a route of its own: per
/// stop, the circular mean of the centre bearings (world frame through the commanded heading),
/// the reading of the beam nearest each scan's centre bearing, its sample variance over the
/// stop's scans; then the weighted rows sqrt(w) [sin, -cos] | sqrt(w) b solved by QR, and the
/// covariance (H' W H)^-1 scaled by the weighted residual variance over K - 2.
struct HandBuilt {
  Eigen::Vector2d centre;
  Eigen::Matrix2d covariance;
};
HandBuilt handBuiltWls(const LandmarkObservations& obs, int id, double sigma_s,
                       double sigma_theta) {
  struct Stop {
    double s = 0, c = 0, sum = 0, sum2 = 0;
    int n = 0;
  };
  std::map<std::size_t, Stop> stops;
  for (const auto& x : obs.sightings) {
    if (x.landmark != id) continue;
    std::size_t nearest = 0;
    for (std::size_t j = 0; j < x.beams.size(); ++j)
      if (std::abs(wrapAngle(x.beams[j].angle_rad - x.bearing_rad)) <
          std::abs(wrapAngle(x.beams[nearest].angle_rad - x.bearing_rad)))
        nearest = j;
    Stop& st = stops[x.stop];
    st.s += std::sin(x.bearing_rad);
    st.c += std::cos(x.bearing_rad);
    st.sum += x.beams[nearest].range_m;
    st.sum2 += x.beams[nearest].range_m * x.beams[nearest].range_m;
    ++st.n;
  }
  const auto k = static_cast<Eigen::Index>(stops.size());
  Eigen::MatrixXd A(k, 2);
  Eigen::VectorXd rhs(k), w(k);
  Eigen::Index i = 0;
  for (const auto& [stop, st] : stops) {
    const Pose2& p = obs.commanded[stop];
    const double theta = p.yaw_rad + std::atan2(st.s, st.c);
    const double mean = st.sum / st.n;
    const double var = (st.sum2 - st.n * mean * mean) / (st.n - 1);
    // Alhashimi et al. 2021 eq. 25
    w(i) = 1.0 / (sigma_s * sigma_s) + 1.0 / (sigma_theta * sigma_theta * var);
    A(i, 0) = std::sqrt(w(i)) * std::sin(theta);
    A(i, 1) = -std::sqrt(w(i)) * std::cos(theta);
    rhs(i) = std::sqrt(w(i)) * (std::sin(theta) * p.x_m - std::cos(theta) * p.y_m);
    ++i;
  }
  HandBuilt h;
  h.centre = A.colPivHouseholderQr().solve(rhs);
  const Eigen::VectorXd r = A * h.centre - rhs;  // sqrt(w) times the signed line distances
  h.covariance = (A.transpose() * A).inverse() * (r.squaredNorm() / static_cast<double>(k - 2));
  return h;
}

TEST(Triangulation,
     PaperWeightsOnNoisyDataWithSeveralScansPerStopMatchAHandBuiltWeightedLeastSquares) {
  // Noisy bearings, positions and ranges, five scans per stop: the eq. 25 weights come from the
  // sample variance of each stop's readings (noise-free data would take the fallback weights).
  auto cfg = noiseFree(Pose2{0.2, -0.1, deg2rad(10.0)});
  cfg.path.scans_per_stop = 5;
  cfg.path.sigma_s_m = 0.02;
  cfg.sigma_theta_rad = deg2rad(1.0);
  cfg.model.noise.kind = NoiseKind::squared;
  cfg.model.noise.sigma_e = 0.0019176;  // 2 cm at 3 m
  cfg.beams = true;
  TriangulationConfig tc;
  tc.weights = LineWeights::paper;
  tc.sigma_s_m = 0.02;
  tc.sigma_theta_rad = deg2rad(1.0);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const auto obs = simulation::simulateLandmarkLevel(cfg, seed).obs;
    const auto est = triangulateAll(obs, tc);
    ASSERT_EQ(est.size(), cfg.landmarks.size());
    for (const auto& e : est) {
      SCOPED_TRACE(e.id);
      ASSERT_TRUE(e.ok()) << e.message;
      const HandBuilt h = handBuiltWls(obs, e.id, tc.sigma_s_m, tc.sigma_theta_rad);
      EXPECT_NEAR(e.x_m, h.centre.x(), 1e-9);
      EXPECT_NEAR(e.y_m, h.centre.y(), 1e-9);
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          EXPECT_NEAR(e.covariance(a, b), h.covariance(a, b), 1e-9 * h.covariance.norm());
      // And the estimate is where the landmark is. (Not within k standard deviations of this
      // covariance: the eq. 25 weights are not the inverse variances of the line residuals,
      // sigma_s^2 + d^2 sigma_theta^2, so the residual-scaled covariance understates the scatter.)
      // Along the line of sight a landmark at d from a path of length b is placed to about
      // d^2 sigma_theta / b: 10 cm for the farthest here (4 m, 2.7 m, 1 degree); allow 15 cm.
      const Cylinder& c = cfg.landmarks[static_cast<std::size_t>(e.id - 1)];
      EXPECT_LT(std::hypot(e.x_m - c.x_m, e.y_m - c.y_m), 0.15);
    }
  }
}

TEST(Triangulation, LandmarkOnThePathLineIsDegenerate) {
  auto cfg = noiseFree(Pose2{});
  cfg.landmarks = {{6.0, 0.001, 0.12}};
  cfg.model.range_max_m = 20.0;
  const auto e =
      triangulateAll(simulation::simulateLandmarkLevel(cfg, 1).obs, TriangulationConfig{});
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].status, TriangulationStatus::degenerate_geometry);
  EXPECT_NE(e[0].message.find("path line"), std::string::npos);
}

TEST(Triangulation, SeenFromTooFewStops) {
  auto cfg = noiseFree(Pose2{});
  cfg.path.stops = 2;
  const auto e =
      triangulateAll(simulation::simulateLandmarkLevel(cfg, 1).obs, TriangulationConfig{});
  ASSERT_FALSE(e.empty());
  for (const auto& l : e) EXPECT_EQ(l.status, TriangulationStatus::too_few_stops);
}

}  // namespace
}  // namespace lidarcal::calibration
