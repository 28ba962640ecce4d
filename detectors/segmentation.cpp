// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/stats_util.hpp"

namespace lidarcal::detectors {

void SegmentationConfig::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("SegmentationConfig.") + field + ": " + what);
  };
  if (!(gap_m > 0.0) || !std::isfinite(gap_m)) fail("gap_m", "must be > 0");
  if (!(gap_per_m >= 0.0) || !std::isfinite(gap_per_m)) fail("gap_per_m", "must be >= 0");
  if (max_missing_beams < 0) fail("max_missing_beams", "must be >= 0");
  if (!(breakpoint_angle_rad >= 0.0 && breakpoint_angle_rad < 1.5707963267948966))
    fail("breakpoint_angle_rad", "must be in [0, pi/2)");
  if (!(breakpoint_noise_m >= 0.0) || !std::isfinite(breakpoint_noise_m))
    fail("breakpoint_noise_m", "must be >= 0");
  if (!(breakpoint_noise_per_m2 >= 0.0) || !std::isfinite(breakpoint_noise_per_m2))
    fail("breakpoint_noise_per_m2", "must be >= 0");
}

namespace {

bool valid(const pcl::PointXYZI& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

/// Angle between the beams of two returns, radians, in [0, pi].
double beamAngle(const pcl::PointXYZI& a, const pcl::PointXYZI& b) {
  return std::abs(
      std::atan2(double(a.x) * b.y - double(a.y) * b.x, double(a.x) * b.x + double(a.y) * b.y));
}

bool neighbours(const pcl::PointXYZI& a, const pcl::PointXYZI& b, const SegmentationConfig& cfg) {
  const double ra = std::hypot(a.x, a.y), rb = std::hypot(b.x, b.y);
  double gap = cfg.gap_m + cfg.gap_per_m * 0.5 * (ra + rb);
  const double dphi = beamAngle(a, b);
  if (cfg.breakpoint_angle_rad > 0.0 && dphi < cfg.breakpoint_angle_rad) {
    const double r = std::min(ra, rb);
    const double abd = r * std::sin(dphi) / std::sin(cfg.breakpoint_angle_rad - dphi) +
                       cfg.breakpoint_noise_m + cfg.breakpoint_noise_per_m2 * r * r;
    gap = std::min(gap, abd);
  }
  return std::hypot(double(a.x) - b.x, double(a.y) - b.y) <= gap;
}

}  // namespace

std::vector<pcl::Indices> segmentScan(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                                      const SegmentationConfig& cfg) {
  cfg.validate();
  std::vector<pcl::Indices> clusters;
  const auto n = static_cast<int>(cloud.size());
  int last = -1;
  for (int i = 0; i < n; ++i) {
    if (!valid(cloud[i])) continue;
    const bool join = last >= 0 && i - last - 1 <= cfg.max_missing_beams &&
                      neighbours(cloud[last], cloud[i], cfg);
    if (!join) clusters.emplace_back();
    clusters.back().push_back(i);
    last = i;
  }
  // Close the circle: the last cluster continues into the first one.
  if (clusters.size() >= 2) {
    const int first = clusters.front().front(), end = clusters.back().back();
    if ((n - 1 - end) + first <= cfg.max_missing_beams &&
        neighbours(cloud[end], cloud[first], cfg)) {
      pcl::Indices merged = std::move(clusters.back());
      merged.insert(merged.end(), clusters.front().begin(), clusters.front().end());
      clusters.pop_back();
      clusters.front() = std::move(merged);
    }
  }
  return clusters;
}

double estimateAngularStep(const pcl::PointCloud<pcl::PointXYZI>& cloud) {
  std::vector<double> steps;
  steps.reserve(cloud.size());
  for (std::size_t i = 1; i < cloud.size(); ++i) {
    const auto &a = cloud[i - 1], &b = cloud[i];
    if (!valid(a) || !valid(b)) continue;
    steps.push_back(beamAngle(a, b));
  }
  return steps.empty() ? 0.0 : upperMedian(std::move(steps));
}

}  // namespace lidarcal::detectors
