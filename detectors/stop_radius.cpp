// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/stop_radius.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/pose2.hpp"
#include "detectors/circle_fit.hpp"
#include "detectors/line_fit.hpp"
#include "detectors/segmentation.hpp"

namespace lidarcal::detectors {

namespace {

/// A cluster of one scan that may be a thin pole: its points (sensor frame) and mean.
struct Candidate {
  std::size_t scan = 0;
  std::vector<Eigen::Vector2d> points;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  double range_m = 0.0;
};

std::vector<Candidate> candidatesOf(const pcl::PointCloud<pcl::PointXYZI>& cloud, std::size_t scan,
                                    const DetectionConfig& cfg) {
  std::vector<Candidate> out;
  for (const auto& idx : segmentScan(cloud, cfg.segmentation)) {
    if (idx.size() < 3) continue;
    Candidate c;
    c.scan = scan;
    for (auto i : idx) {
      const auto& p = cloud[static_cast<std::size_t>(i)];
      c.points.emplace_back(p.x, p.y);
      c.mean += c.points.back();
    }
    c.mean /= static_cast<double>(c.points.size());
    c.range_m = c.mean.norm();
    // Width across the line of sight (bearings are exact): no wider than the largest pole.
    const double b0 = std::atan2(c.points.front().y(), c.points.front().x());
    const double b1 = std::atan2(c.points.back().y(), c.points.back().x());
    if (c.range_m * std::abs(wrapAngle(b1 - b0)) > 2.0 * cfg.radius_max_m * cfg.extent_factor)
      continue;
    if (cfg.threshold(c.range_m) > cfg.max_threshold_to_radius * cfg.radius_max_m) continue;
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

std::vector<RadiusHint> pooledStopRadii(
    const std::vector<const pcl::PointCloud<pcl::PointXYZI>*>& scans, const DetectionConfig& cfg) {
  std::vector<RadiusHint> out;
  if (scans.size() < 2) return out;
  std::vector<Candidate> cands;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    auto c = candidatesOf(*scans[s], s, cfg);
    std::move(c.begin(), c.end(), std::back_inserter(cands));
  }
  // Groups: single linkage of the means within t(range) + 2 cm (one pose: only noise moves them).
  std::vector<std::size_t> parent(cands.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t a = 0; a < cands.size(); ++a)
    for (std::size_t b = a + 1; b < cands.size(); ++b)
      if ((cands[a].mean - cands[b].mean).norm() <= cfg.threshold(cands[a].range_m) + 0.02) {
        const std::size_t ra = find(a), rb = find(b);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      }
  std::vector<std::vector<std::size_t>> groups(cands.size());
  for (std::size_t k = 0; k < cands.size(); ++k) groups[find(k)].push_back(k);
  for (const auto& g : groups) {
    if (g.empty()) continue;
    std::vector<std::size_t> seen;
    for (auto k : g) seen.push_back(cands[k].scan);
    std::sort(seen.begin(), seen.end());
    // two in one scan: not one pole
    if (std::adjacent_find(seen.begin(), seen.end()) != seen.end()) continue;
    if (seen.size() < 2 || 2 * seen.size() < scans.size()) continue;
    pcl::PointCloud<pcl::PointXYZ> pooled;
    double range = 0.0;
    for (auto k : g) {
      for (const auto& p : cands[k].points)
        pooled.push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f));
      range += cands[k].range_m / static_cast<double>(g.size());
    }
    const double t = cfg.threshold(range);
    CircleFitConfig cc;
    cc.inlier_threshold_m = t;
    cc.radius_min_m = cfg.radius_min_m;
    cc.radius_max_m = cfg.radius_max_m;
    cc.seen_from = Eigen::Vector2d::Zero();
    cc.ransac_min_points = cfg.ransac_min_points;
    cc.max_iterations = cfg.max_iterations;
    pcl::Indices all(pooled.size());
    std::iota(all.begin(), all.end(), 0);
    const CircleFit fit = fitCircle(pooled, all, cc);
    if (fit.status != FitStatus::ok || fit.free_status != FitStatus::ok) continue;
    const double n = static_cast<double>(fit.inliers.size());
    if (n < cfg.min_inlier_fraction * static_cast<double>(pooled.size()) ||
        fit.rms_m > cfg.max_rms_fraction * t)
      continue;
    const double p_free = n > 3.0 ? std::sqrt(n / (n - 3.0)) : 0.0;
    const double stddev = fit.free_radius_sensitivity * std::max(fit.free_rms_m * p_free, t / 3.0);
    if (!(stddev <= cfg.max_radius_uncertainty * fit.free_circle.radius_m)) continue;
    // A flat face (wall, box) is no pole: a straight line must not fit the pooled points as well.
    std::vector<Eigen::Vector2d> in;
    for (auto i : fit.inliers)
      in.emplace_back(pooled[static_cast<std::size_t>(i)].x, pooled[static_cast<std::size_t>(i)].y);
    if (totalLeastSquaresLine(in).rms_m <= fit.free_rms_m) continue;
    out.push_back(RadiusHint{fit.free_circle.x_m, fit.free_circle.y_m, fit.free_circle.radius_m});
  }
  return out;
}

}  // namespace lidarcal::detectors
