// SPDX-License-Identifier: BSD-3-Clause
// Circle fitting against closed forms and PCL's own model: PCL-style known-circle cases,
// degenerate inputs, short arcs, fixed radius, rigid motions, float precision far from the origin.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include "common/pose2.hpp"
#include "detectors/circle_fit.hpp"

namespace lidarcal::detectors {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// n points on the arc [a0, a1] of the circle, plus Gaussian radial noise sigma.
Cloud arc(const Circle2& circle, double a0_rad, double a1_rad, int n, double sigma = 0.0,
          unsigned seed = 1) {
  const double cx = circle.x_m, cy = circle.y_m, r = circle.radius_m;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Cloud c;
  for (int i = 0; i < n; ++i) {
    const double a = a0_rad + (a1_rad - a0_rad) * i / (n - 1);
    const double rr = r + sigma * noise(rng);
    c.push_back(pcl::PointXYZ(static_cast<float>(cx + rr * std::cos(a)),
                              static_cast<float>(cy + rr * std::sin(a)), 0.0f));
  }
  return c;
}

pcl::Indices all(const Cloud& c) {
  pcl::Indices idx(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) idx[i] = static_cast<pcl::index_t>(i);
  return idx;
}

// PCL's own test idea (test_sample_consensus_quadric_models: circle 2D): points on a known
// circle plus one far outlier; RANSAC keeps exactly the circle points and the coefficients.
TEST(FitCircle, KnownCirclePlusOneOutlierPclStyle) {
  Cloud c = arc({2.5, -3.0, 1.5}, 0.0, 2.0 * kPi * 16.0 / 17.0, 17);
  c.push_back(pcl::PointXYZ(-5.0f, 7.0f, 0.0f));  // index 17: the outlier
  CircleFitConfig cfg;
  cfg.inlier_threshold_m = 0.01;
  const CircleFit fit = fitCircle(c, all(c), cfg);
  ASSERT_EQ(fit.status, FitStatus::ok) << fit.message;
  EXPECT_TRUE(fit.used_ransac);
  ASSERT_EQ(fit.inliers.size(), 17u);
  for (int i = 0; i < 17; ++i) EXPECT_EQ(fit.inliers[static_cast<std::size_t>(i)], i);
  EXPECT_NEAR(fit.circle.x_m, 2.5, 1e-5);
  EXPECT_NEAR(fit.circle.y_m, -3.0, 1e-5);
  EXPECT_NEAR(fit.circle.radius_m, 1.5, 1e-5);
  EXPECT_LT(fit.rms_m, 1e-6);
}

// The oracle: PCL's SACSegmentation with its own optimiser agrees on clean data.
TEST(FitCircle, AgreesWithPclsOptimisedModelOnCleanArcs) {
  for (unsigned seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    const double cx = u(rng), cy = u(rng), r = 0.2 + std::abs(u(rng)) / 3.0;
    const double a0 = u(rng);
    const Cloud::Ptr c(new Cloud(arc({cx, cy, r}, a0, a0 + 2.5, 40, 0.001, seed)));
    pcl::SACSegmentation<pcl::PointXYZ> seg(false);
    seg.setModelType(pcl::SACMODEL_CIRCLE2D);
    seg.setMethodType(pcl::SAC_RANSAC);
    seg.setDistanceThreshold(0.005);
    seg.setMaxIterations(1000);
    seg.setInputCloud(c);
    pcl::PointIndices inl;
    pcl::ModelCoefficients coef;
    seg.segment(inl, coef);
    ASSERT_EQ(coef.values.size(), 3u);
    CircleFitConfig cfg;
    cfg.inlier_threshold_m = 0.005;
    const CircleFit fit = fitCircle(*c, all(*c), cfg);
    ASSERT_EQ(fit.status, FitStatus::ok);
    EXPECT_NEAR(fit.circle.x_m, coef.values[0], 2e-3);
    EXPECT_NEAR(fit.circle.y_m, coef.values[1], 2e-3);
    EXPECT_NEAR(fit.circle.radius_m, coef.values[2], 2e-3);
    // And both are near the truth (noise 1 mm).
    EXPECT_NEAR(fit.circle.radius_m, r, 3e-3);
  }
}

TEST(FitCircle, ArcsOf60DegreesRecoverCentreAndRadius) {
  // Noise-free: exact to float rounding of the points.
  const Cloud c = arc({1.0, 2.0, 0.12}, 0.3, 0.3 + deg2rad(60.0), 10);
  const CircleFit exact = fitCircle(c, all(c), CircleFitConfig{});
  ASSERT_EQ(exact.status, FitStatus::ok) << exact.message;
  EXPECT_NEAR(exact.circle.x_m, 1.0, 1e-5);
  EXPECT_NEAR(exact.circle.y_m, 2.0, 1e-5);
  EXPECT_NEAR(exact.circle.radius_m, 0.12, 1e-5);
  // With noise sigma = 0.5 mm on 30 points: errors stay within a few sigma of the fit's own
  // uncertainty (for a 60-degree arc the radius is about 10x less certain than the noise).
  for (unsigned seed = 1; seed <= 30; ++seed) {
    SCOPED_TRACE(seed);
    const Cloud n = arc({-0.4, 0.7, 0.12}, 1.0, 1.0 + deg2rad(60.0), 30, 0.0005, seed);
    CircleFitConfig cfg;
    cfg.inlier_threshold_m = 0.003;
    const CircleFit fit = fitCircle(n, all(n), cfg);
    ASSERT_EQ(fit.status, FitStatus::ok) << fit.message;
    EXPECT_EQ(fit.inliers.size(), 30u);
    const double bound = 5.0 * 0.0005 * fit.free_radius_sensitivity;
    EXPECT_NEAR(fit.circle.radius_m, 0.12, bound);
    EXPECT_NEAR(std::hypot(fit.circle.x_m + 0.4, fit.circle.y_m - 0.7), 0.0, 1.5 * bound);
  }
}

TEST(FitCircle, FloatPointsFarFromTheOriginStillFitExactly) {
  // Metres away from the origin, float coordinates keep about 1e-6 relative precision; the
  // points are centred before PCL sees them.
  const Cloud c = arc({80.0, -60.0, 0.1}, 0.0, deg2rad(90.0), 12);
  const CircleFit fit = fitCircle(c, all(c), CircleFitConfig{});
  ASSERT_EQ(fit.status, FitStatus::ok) << fit.message;
  EXPECT_NEAR(fit.circle.radius_m, 0.1, 2e-4);
  EXPECT_NEAR(fit.circle.x_m, 80.0, 2e-4);
}

TEST(FitCircle, FixedRadiusFitsTheCentreAndReportsTheFreeFitToo) {
  const Cloud c = arc({2.0, 0.5, 0.12}, kPi - 1.2, kPi + 1.2, 9);  // the side facing the origin
  CircleFitConfig cfg;
  cfg.fixed_radius_m = 0.12;
  cfg.seen_from = Eigen::Vector2d::Zero();
  const CircleFit fit = fitCircle(c, all(c), cfg);
  ASSERT_EQ(fit.status, FitStatus::ok) << fit.message;
  EXPECT_DOUBLE_EQ(fit.circle.radius_m, 0.12);
  EXPECT_NEAR(fit.circle.x_m, 2.0, 1e-5);
  EXPECT_NEAR(fit.circle.y_m, 0.5, 1e-5);
  EXPECT_EQ(fit.free_status, FitStatus::ok);
  EXPECT_NEAR(fit.free_circle.radius_m, 0.12, 1e-5);
}

TEST(FitCircle, FixedRadiusWithThreePointsStartsBehindTheArc) {
  // Three points only (a far pole): the centre lies one radius behind them, not in front.
  const Cloud c = arc({4.0, 0.0, 0.12}, kPi - 0.5, kPi + 0.5, 3);
  CircleFitConfig cfg;
  cfg.fixed_radius_m = 0.12;
  cfg.seen_from = Eigen::Vector2d::Zero();
  const CircleFit fit = fitCircle(c, all(c), cfg);
  ASSERT_EQ(fit.status, FitStatus::ok) << fit.message;
  EXPECT_NEAR(fit.circle.x_m, 4.0, 1e-5);
  EXPECT_NEAR(fit.circle.y_m, 0.0, 1e-5);
}

TEST(FitCircle, ConcaveArcSeenFromInsideIsTheWrongSide) {
  // The sensor inside a round room: the arc curves around it.
  const Cloud c = arc({0.0, 0.0, 2.0}, -0.3, 0.3, 12);
  CircleFitConfig cfg;
  cfg.seen_from = Eigen::Vector2d(0.5, 0.0);
  const CircleFit fit = fitCircle(c, all(c), cfg);
  EXPECT_EQ(fit.status, FitStatus::wrong_side);
  EXPECT_FALSE(fit.message.empty());
}

TEST(FitCircle, RadiusOutsideTheLimitsIsAStatus) {
  const Cloud c = arc({0.0, 0.0, 1.0}, 0.0, 3.0, 20);
  CircleFitConfig cfg;
  cfg.radius_min_m = 2.0;
  cfg.radius_max_m = 3.0;
  const CircleFit fit = fitCircle(c, all(c), cfg);
  EXPECT_TRUE(fit.status == FitStatus::no_consensus ||
              fit.status == FitStatus::radius_out_of_limits)
      << toString(fit.status);
  EXPECT_FALSE(fit.message.empty());
  // Below ransac_min_points the refinement itself is checked against the limits.
  const Cloud few = arc({0.0, 0.0, 1.0}, 0.0, 3.0, 4);
  EXPECT_EQ(fitCircle(few, all(few), cfg).status, FitStatus::radius_out_of_limits);
}

// PCL's trap: the optimised circle can leave the radius limits (and then select no inlier). Ours
// falls back to RANSAC's unoptimised model, which respects the limits, and keeps its inliers.
TEST(FitCircle, RefinementLeavingTheLimitsFallsBackToTheRansacModel) {
  // Noise makes some minimal samples fall inside the limits; the least-squares circle does not.
  const Cloud c = arc({0.0, 0.0, 1.0}, 0.0, kPi / 2.0, 30, 0.01, 5);
  CircleFitConfig cfg;
  cfg.inlier_threshold_m = 0.03;
  cfg.radius_min_m = 0.5;
  cfg.radius_max_m = 0.97;  // the true radius (1.0) is just outside
  const CircleFit fit = fitCircle(c, all(c), cfg);
  ASSERT_EQ(fit.status, FitStatus::ok) << fit.message;
  EXPECT_TRUE(fit.used_ransac);
  EXPECT_TRUE(fit.refinement_rejected);
  EXPECT_LE(fit.circle.radius_m, 0.97);
  EXPECT_GE(fit.inliers.size(), 20u);
}

TEST(FitCircle, RigidMotionMovesTheCentreTheSameWay) {
  const Cloud base = arc({0.3, -0.2, 0.15}, 0.2, 2.5, 25, 0.002, 3);
  const CircleFit a = fitCircle(base, all(base), CircleFitConfig{});
  ASSERT_EQ(a.status, FitStatus::ok);
  const double yaw = 0.7, tx = 1.25, ty = -0.5;
  Cloud moved;
  for (const auto& p : base)
    moved.push_back(
        pcl::PointXYZ(static_cast<float>(tx + std::cos(yaw) * p.x - std::sin(yaw) * p.y),
                      static_cast<float>(ty + std::sin(yaw) * p.x + std::cos(yaw) * p.y), 0.0f));
  const CircleFit b = fitCircle(moved, all(moved), CircleFitConfig{});
  ASSERT_EQ(b.status, FitStatus::ok);
  EXPECT_NEAR(b.circle.x_m, tx + std::cos(yaw) * a.circle.x_m - std::sin(yaw) * a.circle.y_m, 1e-5);
  EXPECT_NEAR(b.circle.y_m, ty + std::sin(yaw) * a.circle.x_m + std::cos(yaw) * a.circle.y_m, 1e-5);
  EXPECT_NEAR(b.circle.radius_m, a.circle.radius_m, 1e-5);
}

TEST(FitCircle, SameInputSameResult) {
  Cloud c = arc({1.0, 1.0, 0.3}, 0.0, 4.0, 50, 0.003, 9);
  for (int i = 0; i < 10; ++i) c.push_back(pcl::PointXYZ(0.1f * static_cast<float>(i), 3.0f, 0.0f));
  CircleFitConfig cfg;
  cfg.inlier_threshold_m = 0.01;
  const CircleFit a = fitCircle(c, all(c), cfg), b = fitCircle(c, all(c), cfg);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.circle.x_m, b.circle.x_m);
  EXPECT_EQ(a.circle.radius_m, b.circle.radius_m);
}

TEST(FitCircle, IndicesSelectTheSubsetAndNanPointsAreSkipped) {
  Cloud c = arc({0.0, 0.0, 0.5}, 0.0, 2.0, 10);
  c.push_back(pcl::PointXYZ(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f));
  c.push_back(pcl::PointXYZ(9.0f, 9.0f, 0.0f));
  const pcl::Indices idx{0, 2, 4, 6, 8, 10};  // 10 is NaN; 11 is never looked at
  const CircleFit fit = fitCircle(c, idx, CircleFitConfig{});
  ASSERT_EQ(fit.status, FitStatus::ok);
  EXPECT_EQ(fit.inliers, (pcl::Indices{0, 2, 4, 6, 8}));
  EXPECT_NEAR(fit.circle.radius_m, 0.5, 1e-5);
}

TEST(FitCircle, BadConfigurationIsRefused) {
  const Cloud c = arc({0.0, 0.0, 0.5}, 0.0, 2.0, 10);
  CircleFitConfig cfg;
  // PCL would silently ignore the limits
  cfg.radius_max_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(fitCircle(c, all(c), cfg), std::invalid_argument);
  cfg = CircleFitConfig{};
  cfg.inlier_threshold_m = 0.0;
  EXPECT_THROW(fitCircle(c, all(c), cfg), std::invalid_argument);
  const pcl::Indices outside{0, 99};
  EXPECT_THROW(fitCircle(c, outside, CircleFitConfig{}), std::out_of_range);
}

// Degenerate inputs: a status, never a crash, whatever the configuration.
struct DegenerateCase {
  const char* name;
  std::vector<std::pair<float, float>> points;
  FitStatus expected;
};

class DegenerateCircle : public ::testing::TestWithParam<DegenerateCase> {};

TEST_P(DegenerateCircle, GivesAStatusNotACrash) {
  Cloud c;
  for (const auto& [x, y] : GetParam().points) c.push_back(pcl::PointXYZ(x, y, 0.0f));
  for (int variant = 0; variant < 3; ++variant) {
    SCOPED_TRACE(variant);
    CircleFitConfig cfg;
    if (variant >= 1) cfg.fixed_radius_m = 0.12;
    if (variant == 2) cfg.seen_from = Eigen::Vector2d::Zero();
    const CircleFit fit = fitCircle(c, all(c), cfg);
    EXPECT_EQ(fit.status, GetParam().expected) << toString(fit.status);
    EXPECT_FALSE(fit.message.empty());
    EXPECT_TRUE(fit.inliers.empty());
  }
}

const float kNaN = std::numeric_limits<float>::quiet_NaN();

INSTANTIATE_TEST_SUITE_P(
    Inputs, DegenerateCircle,
    ::testing::Values(
        DegenerateCase{"empty", {}, FitStatus::too_few_points},
        DegenerateCase{"one_point", {{1.0f, 1.0f}}, FitStatus::too_few_points},
        DegenerateCase{"two_points", {{1.0f, 1.0f}, {2.0f, 1.0f}}, FitStatus::too_few_points},
        DegenerateCase{
            "nan_only", {{kNaN, kNaN}, {kNaN, 1.0f}, {kNaN, kNaN}}, FitStatus::too_few_points},
        DegenerateCase{"all_equal",
                       {{1.0f, 2.0f}, {1.0f, 2.0f}, {1.0f, 2.0f}, {1.0f, 2.0f}},
                       FitStatus::degenerate},
        DegenerateCase{"two_distinct_duplicated",
                       {{1.0f, 2.0f},
                        {1.0f, 2.0f},
                        {3.0f, 2.0f},
                        {3.0f, 2.0f},
                        {1.0f, 2.0f},
                        {3.0f, 2.0f},
                        {1.0f, 2.0f}},
                       FitStatus::degenerate},
        DegenerateCase{
            "collinear_three", {{0.0f, 0.0f}, {1.0f, 1.0f}, {2.0f, 2.0f}}, FitStatus::degenerate},
        DegenerateCase{"collinear_many",
                       {{0.5f, 1.0f},
                        {0.6f, 1.2f},
                        {0.7f, 1.4f},
                        {0.8f, 1.6f},
                        {0.9f, 1.8f},
                        {1.0f, 2.0f},
                        {1.1f, 2.2f},
                        {1.2f, 2.4f}},
                       FitStatus::degenerate},
        DegenerateCase{"horizontal_line",
                       {{0.0f, 1.0f}, {1.0f, 1.0f}, {2.0f, 1.0f}, {3.0f, 1.0f}},
                       FitStatus::degenerate}),
    [](const auto& p) { return std::string(p.param.name); });

TEST(Taubin, ExactOnCirclePointsAndNothingOnALine) {
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i < 7; ++i)
    pts.emplace_back(3.0 + 0.4 * std::cos(0.3 * i), -1.0 + 0.4 * std::sin(0.3 * i));
  const auto c = taubinCircle(pts);
  ASSERT_TRUE(c);
  EXPECT_NEAR(c->x_m, 3.0, 1e-9);
  EXPECT_NEAR(c->y_m, -1.0, 1e-9);
  EXPECT_NEAR(c->radius_m, 0.4, 1e-9);
  EXPECT_FALSE(taubinCircle({{0, 0}, {1, 1}, {2, 2}, {3, 3}}));
  EXPECT_FALSE(taubinCircle({{0, 0}, {1, 1}}));
}

TEST(RefineCircle, GeometricFitReachesTheMinimumFromAPoorStart) {
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i < 20; ++i) pts.emplace_back(0.25 * std::cos(0.1 * i), 0.25 * std::sin(0.1 * i));
  const GeometricFit g = refineCircle(pts, Circle2{0.05, -0.04, 0.4}, std::nullopt);
  EXPECT_TRUE(g.converged);
  EXPECT_NEAR(g.circle.x_m, 0.0, 1e-9);
  EXPECT_NEAR(g.circle.radius_m, 0.25, 1e-9);
  EXPECT_LT(g.rms_m, 1e-10);
  const GeometricFit f = refineCircle(pts, Circle2{0.05, -0.04, 0.0}, 0.25);
  EXPECT_NEAR(f.circle.x_m, 0.0, 1e-9);
  EXPECT_NEAR(f.circle.y_m, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(f.circle.radius_m, 0.25);
}

}  // namespace
}  // namespace lidarcal::detectors
