// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/ransac.hpp"

#include <limits>
#include <memory>
#include <numeric>

#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_circle.h>
#include <pcl/sample_consensus/sac_model_line.h>

namespace lidarcal::detectors {

namespace {

/// Every point's index, as pcl::PCLBase::initCompute makes them when none are given.
pcl::Indices allIndices(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  pcl::Indices all(cloud.size());
  std::iota(all.begin(), all.end(), 0);
  return all;
}

/// RANSAC over a model: the calls pcl::SACSegmentation::segment makes with RANSAC and without
/// optimised coefficients (its initSAC sets the probability and the iterations when they differ
/// from the defaults, which is the same as setting them).
bool run(const pcl::SampleConsensusModel<pcl::PointXYZ>::Ptr& model, const RansacSettings& s,
         pcl::Indices& inliers, Eigen::VectorXf& coefficients) {
  pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model, s.threshold_m);
  ransac.setProbability(s.probability);
  if (s.max_iterations != -1) ransac.setMaxIterations(s.max_iterations);
  inliers.clear();
  coefficients.resize(0);
  if (!ransac.computeModel(0)) return false;
  ransac.getInliers(inliers);
  ransac.getModelCoefficients(coefficients);
  return true;
}

}  // namespace

bool ransacCircle2D(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
                    const RansacSettings& settings, double radius_min_m, double radius_max_m,
                    pcl::Indices& inliers, Eigen::VectorXf& coefficients) {
  if (!cloud || cloud->empty()) return false;
  auto model = std::make_shared<pcl::SampleConsensusModelCircle2D<pcl::PointXYZ>>(
      cloud, allIndices(*cloud), false);
  // SACSegmentation sets the limits only when both differ from the model's unlimited defaults.
  double lo = 0.0, hi = 0.0;
  model->getRadiusLimits(lo, hi);
  if (radius_min_m != lo && radius_max_m != hi) model->setRadiusLimits(radius_min_m, radius_max_m);
  return run(model, settings, inliers, coefficients);
}

bool ransacLine(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
                const RansacSettings& settings, pcl::Indices& inliers,
                Eigen::VectorXf& coefficients) {
  if (!cloud || cloud->empty()) return false;
  auto model = std::make_shared<pcl::SampleConsensusModelLine<pcl::PointXYZ>>(
      cloud, allIndices(*cloud), false);
  return run(model, settings, inliers, coefficients);
}

}  // namespace lidarcal::detectors
