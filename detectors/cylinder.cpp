// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/cylinder.hpp"

#include <cmath>
#include <stdexcept>

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/passthrough.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/sac_segmentation.h>

namespace lidarcal::detectors {

void CylinderConfig::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("CylinderConfig.") + field + ": " + what);
  };
  if (!(z_max_m > z_min_m)) fail("z_max_m", "must be > z_min_m");
  if (normal_neighbours < 3) fail("normal_neighbours", "must be >= 3");
  if (!(plane_normal_weight >= 0.0 && plane_normal_weight <= 1.0))
    fail("plane_normal_weight", "must be in [0, 1]");
  if (!(plane_threshold_m > 0.0)) fail("plane_threshold_m", "must be > 0");
  if (plane_iterations < 1) fail("plane_iterations", "must be >= 1");
  if (!(normal_weight >= 0.0 && normal_weight <= 1.0)) fail("normal_weight", "must be in [0, 1]");
  if (!(threshold_m > 0.0)) fail("threshold_m", "must be > 0");
  if (iterations < 1) fail("iterations", "must be >= 1");
  // Both limits finite (PCL ignores them otherwise).
  if (!(radius_min_m >= 0.0) || !std::isfinite(radius_min_m))
    fail("radius_min_m", "must be finite and >= 0");
  if (!(radius_max_m > radius_min_m) || !std::isfinite(radius_max_m))
    fail("radius_max_m", "must be finite and > radius_min_m");
}

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Normals = pcl::PointCloud<pcl::Normal>;

/// Indices of the points within the z window (NaN points dropped too).
pcl::IndicesPtr pointsInZWindow(const Cloud::ConstPtr& cloud, const CylinderConfig& cfg) {
  pcl::IndicesPtr kept(new pcl::Indices);
  pcl::PassThrough<pcl::PointXYZ> pass;
  pass.setInputCloud(cloud);
  pass.setFilterFieldName("z");
  pass.setFilterLimits(static_cast<float>(cfg.z_min_m), static_cast<float>(cfg.z_max_m));
  pass.filter(*kept);
  return kept;
}

/// Surface normals from the `k` nearest neighbours.
Normals::Ptr estimateNormals(const Cloud::Ptr& pts, int k) {
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  Normals::Ptr normals(new Normals);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setSearchMethod(tree);
  ne.setInputCloud(pts);
  ne.setKSearch(k);
  ne.compute(*normals);
  return normals;
}

/// The candidate points (indices into pts): with cfg.remove_plane, those off the dominant plane
/// (its coefficients and inlier count into `out`); else all.
pcl::IndicesPtr pointsOffPlane(const Cloud::Ptr& pts, const Normals::Ptr& normals,
                               const CylinderConfig& cfg, CylinderResult& out) {
  pcl::IndicesPtr rest(new pcl::Indices);
  if (!cfg.remove_plane) {
    for (std::size_t i = 0; i < pts->size(); ++i) rest->push_back(static_cast<pcl::index_t>(i));
    return rest;
  }
  pcl::SACSegmentationFromNormals<pcl::PointXYZ, pcl::Normal> plane(/*random=*/false);
  plane.setOptimizeCoefficients(true);
  plane.setModelType(pcl::SACMODEL_NORMAL_PLANE);
  plane.setNormalDistanceWeight(cfg.plane_normal_weight);
  plane.setMethodType(pcl::SAC_RANSAC);
  plane.setMaxIterations(cfg.plane_iterations);
  plane.setDistanceThreshold(cfg.plane_threshold_m);
  plane.setInputCloud(pts);
  plane.setInputNormals(normals);
  pcl::PointIndices plane_inliers;
  pcl::ModelCoefficients plane_coefficients;
  plane.segment(plane_inliers, plane_coefficients);
  if (plane_coefficients.values.size() == 4)
    out.plane = Eigen::Vector4d(plane_coefficients.values[0], plane_coefficients.values[1],
                                plane_coefficients.values[2], plane_coefficients.values[3]);
  out.plane_inliers = plane_inliers.indices.size();
  std::vector<bool> on_plane(pts->size(), false);
  for (auto i : plane_inliers.indices) on_plane[static_cast<std::size_t>(i)] = true;
  for (std::size_t i = 0; i < pts->size(); ++i)
    if (!on_plane[i]) rest->push_back(static_cast<pcl::index_t>(i));
  return rest;
}

/// RANSAC of the cylinder over the candidates `rest`; its axis, radius and inliers (as indices
/// of the input cloud, through `kept`) into `out`.
void fitCylinder(const Cloud::Ptr& pts, const Normals::Ptr& normals, const pcl::IndicesPtr& rest,
                 const pcl::Indices& kept, const CylinderConfig& cfg, CylinderResult& out) {
  pcl::SACSegmentationFromNormals<pcl::PointXYZ, pcl::Normal> seg(/*random=*/false);
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_CYLINDER);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setNormalDistanceWeight(cfg.normal_weight);
  seg.setMaxIterations(cfg.iterations);
  seg.setDistanceThreshold(cfg.threshold_m);
  seg.setRadiusLimits(cfg.radius_min_m, cfg.radius_max_m);
  seg.setInputCloud(pts);
  seg.setInputNormals(normals);
  seg.setIndices(rest);
  pcl::PointIndices inliers;
  pcl::ModelCoefficients c;
  seg.segment(inliers, c);
  if (inliers.indices.empty() || c.values.size() != 7) {
    out.status = FitStatus::no_consensus;
    out.message = "RANSAC found no cylinder with radius in the limits";
    return;
  }
  out.point_on_axis = Eigen::Vector3d(c.values[0], c.values[1], c.values[2]);
  out.axis = Eigen::Vector3d(c.values[3], c.values[4], c.values[5]).normalized();
  out.radius_m = c.values[6];
  out.inliers.reserve(inliers.indices.size());
  for (auto i : inliers.indices) out.inliers.push_back(kept[static_cast<std::size_t>(i)]);
  out.status = FitStatus::ok;
}

}  // namespace

CylinderResult detectCylinder(const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
                              const CylinderConfig& cfg) {
  cfg.validate();
  if (!cloud) throw std::invalid_argument("detectCylinder: no cloud");
  CylinderResult out;
  const pcl::IndicesPtr kept = pointsInZWindow(cloud, cfg);
  out.points_used = kept->size();
  if (kept->size() < static_cast<std::size_t>(cfg.normal_neighbours)) {
    out.message = "only " + std::to_string(kept->size()) + " points in the z window";
    return out;
  }
  // Deliberate copy: normal estimation and the normal-aware models need a dense cloud aligned
  // with the normals; `kept` maps it back to input indices.
  Cloud::Ptr pts(new Cloud);
  pts->reserve(kept->size());
  for (auto i : *kept) pts->push_back((*cloud)[static_cast<std::size_t>(i)]);
  const Normals::Ptr normals = estimateNormals(pts, cfg.normal_neighbours);
  const pcl::IndicesPtr rest = pointsOffPlane(pts, normals, cfg, out);  // indices into pts
  if (rest->size() < 2) {
    out.message = "no points left besides the plane";
    return out;
  }
  fitCylinder(pts, normals, rest, *kept, cfg, out);
  return out;
}

}  // namespace lidarcal::detectors
