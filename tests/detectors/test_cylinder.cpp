// SPDX-License-Identifier: BSD-3-Clause
// 3D cylinders: a synthetic cylinder on a plane (closed form), and PCL's mug scene against the
// numbers PCL's cylinder-segmentation tutorial reports.

#include <cmath>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/filters/passthrough.h>
#include <pcl/io/pcd_io.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/sac_segmentation.h>

#include "common/pose2.hpp"
#include "detectors/cylinder.hpp"
#include "test_util.hpp"

namespace lidarcal::detectors {
namespace {

/// Distance from point p to the line through a along unit u.
double distanceToLine(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                      const Eigen::Vector3d& u) {
  return ((p - a) - (p - a).dot(u) * u).norm();
}

TEST(DetectCylinder, SyntheticCylinderStandingOnAPlane) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> n(0.0, 0.001);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    // Floor z = 0.5 (1.2 x 1.2 m), a vertical cylinder of radius 0.05 m at (0.1, -0.2).
    for (int i = 0; i < 6000; ++i)
      cloud->push_back(pcl::PointXYZ(static_cast<float>(1.2 * u(rng) - 0.6),
                                     static_cast<float>(1.2 * u(rng) - 0.6),
                                     static_cast<float>(0.5 + n(rng))));
    for (int i = 0; i < 3000; ++i) {
      const double a = 2.0 * kPi * u(rng), h = 0.5 + 0.3 * u(rng), r = 0.05 + n(rng);
      cloud->push_back(pcl::PointXYZ(static_cast<float>(0.1 + r * std::cos(a)),
                                     static_cast<float>(-0.2 + r * std::sin(a)),
                                     static_cast<float>(h)));
    }
    CylinderConfig cfg;
    cfg.threshold_m = 0.01;
    cfg.iterations = 2000;
    const CylinderResult res = detectCylinder(cloud, cfg);
    ASSERT_EQ(res.status, FitStatus::ok) << res.message;
    EXPECT_NEAR(res.radius_m, 0.05, 0.003);
    EXPECT_GT(std::abs(res.axis.z()), std::cos(deg2rad(3.0)));
    EXPECT_LT(distanceToLine(Eigen::Vector3d(0.1, -0.2, 0.6), res.point_on_axis, res.axis), 0.004);
    EXPECT_GT(res.inliers.size(), 2500u);
    // Floor points right at the cylinder's foot may lie within the threshold (their normals lean
    // towards the cylinder, so the plane step leaves them); they are few.
    std::size_t floor = 0;
    for (auto i : res.inliers) floor += i < 6000;
    EXPECT_LT(floor, res.inliers.size() / 20);
    EXPECT_NEAR(std::abs(res.plane[2]), 1.0, 1e-2);
  }
}

TEST(DetectCylinder, NoPointsInTheWindowIsAStatus) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 100; ++i) cloud->push_back(pcl::PointXYZ(0.0f, 0.0f, 5.0f));
  const CylinderResult res = detectCylinder(cloud, CylinderConfig{});
  EXPECT_NE(res.status, FitStatus::ok);
  EXPECT_FALSE(res.message.empty());
  CylinderConfig bad;
  bad.radius_max_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(detectCylinder(cloud, bad), std::invalid_argument);
}

// PCL's tutorial (pcl/doc/tutorials/content/cylinder_segmentation.rst) on the same data reports
// radius 0.0396354, axis (0.20495, -0.721649, -0.661225), point (0.0452105, 0.0924601, 0.790215).
// PCL 1.13 running the tutorial's own code finds the same radius within 1 mm but an axis 14
// degrees away, along the table's normal (the documented axis is 14 degrees off it): with a 5 cm
// threshold on a 4 cm mug the axis is loosely constrained and depends on the RANSAC draws of the
// PCL version. So: our pipeline must equal the tutorial's code run here (the oracle), match the
// documented radius and point, and give an axis perpendicular to the table.
TEST(DetectCylinder, FindsTheMugOfPclsTutorial) {
  const auto file = test::sharedData() / "pcl/table_scene_mug_stereo_textured.pcd";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "measured data not found: " << file;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  ASSERT_EQ(pcl::io::loadPCDFile(file.string(), *cloud), 0);
  const CylinderResult res = detectCylinder(cloud, CylinderConfig{});  // the tutorial's settings
  ASSERT_EQ(res.status, FitStatus::ok) << res.message;

  // The oracle: the tutorial's code, step by step.
  pcl::PointCloud<pcl::PointXYZ>::Ptr filtered(new pcl::PointCloud<pcl::PointXYZ>),
      rest(new pcl::PointCloud<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>),
      rest_normals(new pcl::PointCloud<pcl::Normal>);
  pcl::PassThrough<pcl::PointXYZ> pass;
  pass.setInputCloud(cloud);
  pass.setFilterFieldName("z");
  pass.setFilterLimits(0, 1.5);
  pass.filter(*filtered);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setSearchMethod(
      pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
  ne.setInputCloud(filtered);
  ne.setKSearch(50);
  ne.compute(*normals);
  pcl::SACSegmentationFromNormals<pcl::PointXYZ, pcl::Normal> seg;
  pcl::PointIndices::Ptr plane(new pcl::PointIndices), cyl(new pcl::PointIndices);
  pcl::ModelCoefficients plane_c, cyl_c;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_NORMAL_PLANE);
  seg.setNormalDistanceWeight(0.1);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setMaxIterations(100);
  seg.setDistanceThreshold(0.03);
  seg.setInputCloud(filtered);
  seg.setInputNormals(normals);
  seg.segment(*plane, plane_c);
  pcl::ExtractIndices<pcl::PointXYZ> extract;
  extract.setInputCloud(filtered);
  extract.setIndices(plane);
  extract.setNegative(true);
  extract.filter(*rest);
  pcl::ExtractIndices<pcl::Normal> extract_normals;
  extract_normals.setNegative(true);
  extract_normals.setInputCloud(normals);
  extract_normals.setIndices(plane);
  extract_normals.filter(*rest_normals);
  seg.setModelType(pcl::SACMODEL_CYLINDER);
  seg.setMaxIterations(10000);
  seg.setDistanceThreshold(0.05);
  seg.setRadiusLimits(0, 0.1);
  seg.setInputCloud(rest);
  seg.setInputNormals(rest_normals);
  seg.segment(*cyl, cyl_c);
  ASSERT_EQ(cyl_c.values.size(), 7u);
  EXPECT_EQ(res.inliers.size(), cyl->indices.size());
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(res.point_on_axis[k], cyl_c.values[static_cast<std::size_t>(k)], 1e-6);
  EXPECT_NEAR(std::abs(res.axis.dot(
                  Eigen::Vector3d(cyl_c.values[3], cyl_c.values[4], cyl_c.values[5]).normalized())),
              1.0, 1e-9);
  EXPECT_NEAR(res.radius_m, cyl_c.values[6], 1e-7);

  // The documented numbers.
  EXPECT_NEAR(res.radius_m, 0.0396354, 0.002);
  EXPECT_LT(
      distanceToLine(Eigen::Vector3d(0.0452105, 0.0924601, 0.790215), res.point_on_axis, res.axis),
      0.015);
  const Eigen::Vector3d documented_axis =
      Eigen::Vector3d(0.20495, -0.721649, -0.661225).normalized();
  EXPECT_GT(std::abs(res.axis.dot(documented_axis)), std::cos(deg2rad(15.0)));
  // The table (tutorial: -0.0161854, 0.837724, 0.545855, -0.528787), and the mug stands on it.
  const Eigen::Vector3d table = res.plane.head<3>().normalized();
  EXPECT_GT(std::abs(table.dot(Eigen::Vector3d(-0.0161854, 0.837724, 0.545855))), 0.9999);
  EXPECT_GT(std::abs(res.axis.dot(table)), std::cos(deg2rad(3.0)));
}

}  // namespace
}  // namespace lidarcal::detectors
