#include "detectors/walls.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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

void RunWallConfig::validate() const {
  if (!(max_deviation_m > 0.0)) throw std::invalid_argument("RunWallConfig.max_deviation_m: must be > 0");
  if (min_points < 2) throw std::invalid_argument("RunWallConfig.min_points: must be >= 2");
}

std::vector<Wall> findWallsInRun(const std::vector<Eigen::Vector2d>& run, const RunWallConfig& config) {
  config.validate();
  std::vector<Wall> walls;
  const auto min_points = static_cast<std::size_t>(config.min_points);
  const bool trim = config.drop_run_ends && run.size() >= 3;
  const std::size_t first = trim ? 1 : 0, last = trim ? run.size() - 1 : run.size();
  if (last - first < min_points) return walls;
  std::vector<std::pair<std::size_t, std::size_t>> stack{{first, last}};  // pieces [lo, hi) still to check
  while (!stack.empty()) {
    const auto [lo, hi] = stack.back();
    stack.pop_back();
    if (hi - lo < min_points) continue;
    const std::vector<Eigen::Vector2d> pts(run.begin() + static_cast<long>(lo), run.begin() + static_cast<long>(hi));
    const Line2 line = totalLeastSquaresLine(pts);
    const NormalForm nf = normalForm(line);
    double worst = 0.0;
    std::size_t at = lo;
    for (std::size_t k = lo; k < hi; ++k) {
      const Eigen::Vector2d& q = pts[k - lo];
      const double dev = std::abs(q.x() * std::cos(nf.normal_rad) + q.y() * std::sin(nf.normal_rad) - nf.distance_m);
      if (dev > worst) {
        worst = dev;
        at = k;
      }
    }
    if (worst <= config.max_deviation_m) {
      Wall w;
      w.normal_rad = nf.normal_rad;
      w.distance_m = nf.distance_m;
      w.rms_m = line.rms_m;
      for (std::size_t k = lo; k < hi; ++k) w.inliers.push_back(static_cast<pcl::index_t>(k));
      walls.push_back(std::move(w));
    } else {
      const std::size_t cut = std::clamp(at, lo + 1, hi - 1);  // split at the farthest point
      stack.push_back({cut, hi});
      stack.push_back({lo, cut});
    }
  }
  return walls;
}

}  // namespace lidarcal::detectors
