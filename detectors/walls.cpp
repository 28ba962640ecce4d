#include "detectors/walls.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace lidarcal::detectors {

void WallConfig::validate() const {
  segmentation.validate();
  line.validate();
  if (min_points < 2) throw std::invalid_argument("WallConfig.min_points: must be >= 2");
  if (!(min_inlier_fraction > 0.0 && min_inlier_fraction <= 1.0))
    throw std::invalid_argument("WallConfig.min_inlier_fraction: must be in (0, 1]");
  if (!(min_length_m >= 0.0)) throw std::invalid_argument("WallConfig.min_length_m: must be >= 0");
}

std::vector<Wall> findWalls(const pcl::PointCloud<pcl::PointXYZI>& cloud, const WallConfig& config) {
  config.validate();
  std::vector<Wall> walls;
  for (const pcl::Indices& cluster : segmentScan(cloud, config.segmentation)) {
    if (static_cast<int>(cluster.size()) < config.min_points) continue;
    const LineFit fit = fitLine(cloud, cluster, config.line);
    if (fit.status != FitStatus::ok ||
        static_cast<double>(fit.inliers.size()) < config.min_inlier_fraction * static_cast<double>(cluster.size()))
      continue;
    const Eigen::Vector2d& p = fit.line.point;
    const Eigen::Vector2d& u = fit.line.direction;
    double lo = 0.0, hi = 0.0;  // extent of the inliers along the line
    for (const auto i : fit.inliers) {
      const auto& q = cloud[static_cast<std::size_t>(i)];
      const double t = (Eigen::Vector2d(q.x, q.y) - p).dot(u);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    if (hi - lo < config.min_length_m) continue;
    const Eigen::Vector2d foot = p - p.dot(u) * u;  // nearest point of the line to the sensor
    Wall w;
    w.distance_m = foot.norm();
    w.normal_rad = std::atan2(foot.y(), foot.x());
    w.rms_m = fit.line.rms_m;
    w.inliers = fit.inliers;
    std::sort(w.inliers.begin(), w.inliers.end());
    walls.push_back(std::move(w));
  }
  return walls;
}

}  // namespace lidarcal::detectors
