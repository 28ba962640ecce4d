// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/walls.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/pose2.hpp"

namespace lidarcal::detectors {
namespace {

Eigen::Vector2d xy(const pcl::PointCloud<pcl::PointXYZI>& cloud, pcl::index_t i) {
  const auto& p = cloud[static_cast<std::size_t>(i)];
  return {static_cast<double>(p.x), static_cast<double>(p.y)};
}

/// A wall while it is being found: the wall and the inlier threshold its line was fitted with.
struct Piece {
  Wall wall;
  double threshold_m = 0.0;
};

/// The wall of a line fitted to `inliers` (NaN-free), or false when the line passes through the
/// sensor.
bool wallFromLine(const Line2& line, pcl::Indices inliers, Wall& w) {
  const Eigen::Vector2d& p = line.point;
  const Eigen::Vector2d& u = line.direction;
  const Eigen::Vector2d foot = p - p.dot(u) * u;  // nearest point of the line to the sensor
  if (!(foot.norm() > 1e-9)) return false;
  w.distance_m = foot.norm();
  w.normal_rad = std::atan2(foot.y(), foot.x());
  w.rms_m = line.rms_m;
  w.inliers = std::move(inliers);
  std::sort(w.inliers.begin(), w.inliers.end());
  return true;
}

/// The returns of `piece` that are finite.
pcl::Indices finitePoints(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& piece) {
  pcl::Indices out;
  out.reserve(piece.size());
  for (const auto i : piece) {
    const auto& p = cloud[static_cast<std::size_t>(i)];
    if (std::isfinite(p.x) && std::isfinite(p.y)) out.push_back(i);
  }
  return out;
}

/// Whether a line explains `piece` (enough inliers over enough length); fills `out` if so.
bool lineExplains(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& piece,
                  const WallConfig& c, Piece& out) {
  double mean_range = 0.0;
  for (const auto i : piece) mean_range += xy(cloud, i).norm();
  mean_range /= static_cast<double>(piece.size());
  LineFitConfig line = c.line;
  line.inlier_threshold_m =
      c.line.inlier_threshold_m + c.threshold_per_m2 * mean_range * mean_range;
  const LineFit fit = fitLine(cloud, piece, line);
  if (fit.status != FitStatus::ok || static_cast<double>(fit.inliers.size()) <
                                         c.min_inlier_fraction * static_cast<double>(piece.size()))
    return false;
  double lo = 0.0, hi = 0.0;  // extent of the inliers along the line
  for (const auto i : fit.inliers) {
    const double t = (xy(cloud, i) - fit.line.point).dot(fit.line.direction);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  if (hi - lo < c.min_length_m) return false;
  out.threshold_m = line.inlier_threshold_m;
  return wallFromLine(fit.line, fit.inliers, out.wall);
}

/// Split: a piece a line explains is a wall; any other is cut at the point farthest from the
/// chord between its ends (a corner, the edge of an object) and both parts are tried again.
void splitIntoWalls(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& piece,
                    const WallConfig& c, std::vector<Piece>& out) {
  if (static_cast<int>(piece.size()) < c.min_points) return;
  Piece found;
  if (lineExplains(cloud, piece, c, found)) {
    out.push_back(std::move(found));
    return;
  }
  const Eigen::Vector2d a = xy(cloud, piece.front()), b = xy(cloud, piece.back());
  const Eigen::Vector2d along =
      (b - a).norm() > 0.0 ? Eigen::Vector2d((b - a).normalized()) : Eigen::Vector2d::UnitX();
  std::size_t cut = 0;
  double farthest = -1.0;
  for (std::size_t k = 1; k + 1 < piece.size(); ++k) {
    const Eigen::Vector2d q = xy(cloud, piece[k]) - a;
    const double off = std::abs(q.x() * along.y() - q.y() * along.x());
    if (off > farthest) farthest = off, cut = k;
  }
  if (cut == 0) return;
  // The point at the cut (a corner) belongs to neither part.
  const auto mid = piece.begin() + static_cast<std::ptrdiff_t>(cut);
  splitIntoWalls(cloud, pcl::Indices(piece.begin(), mid), c, out);
  splitIntoWalls(cloud, pcl::Indices(mid + 1, piece.end()), c, out);
}

/// A return within the threshold of two walls lies near where they meet (a corner): it is
/// taken from both, whose lines are refitted without it.
void dropSharedPoints(const pcl::PointCloud<pcl::PointXYZI>& cloud, std::vector<Piece>& pieces) {
  std::vector<pcl::index_t> all;
  for (const Piece& p : pieces) all.insert(all.end(), p.wall.inliers.begin(), p.wall.inliers.end());
  std::sort(all.begin(), all.end());
  std::vector<pcl::index_t> shared;
  for (std::size_t k = 1; k < all.size(); ++k)
    if (all[k] == all[k - 1] && (shared.empty() || shared.back() != all[k]))
      shared.push_back(all[k]);
  if (shared.empty()) return;
  for (Piece& p : pieces) {
    pcl::Indices kept;
    std::vector<Eigen::Vector2d> pts;
    for (const auto i : p.wall.inliers)
      if (!std::binary_search(shared.begin(), shared.end(), i))
        kept.push_back(i), pts.push_back(xy(cloud, i));
    if (kept.size() == p.wall.inliers.size() || kept.size() < 2) continue;
    Wall refitted;
    if (wallFromLine(totalLeastSquaresLine(pts), std::move(kept), refitted))
      p.wall = std::move(refitted);
  }
}

/// Merge: walls on one line (normals within merge_angle_rad, distances within the inlier
/// threshold) become one, its line refitted through all their inliers.
void mergeCollinear(const pcl::PointCloud<pcl::PointXYZI>& cloud, const WallConfig& c,
                    std::vector<Piece>& pieces) {
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < pieces.size() && !merged; ++i)
      for (std::size_t j = i + 1; j < pieces.size() && !merged; ++j) {
        const Wall &a = pieces[i].wall, &b = pieces[j].wall;
        const double threshold = std::max(pieces[i].threshold_m, pieces[j].threshold_m);
        if (std::abs(wrapAngle(a.normal_rad - b.normal_rad)) > c.merge_angle_rad ||
            std::abs(a.distance_m - b.distance_m) > threshold)
          continue;
        pcl::Indices all = a.inliers;
        all.insert(all.end(), b.inliers.begin(), b.inliers.end());
        std::vector<Eigen::Vector2d> pts;
        pts.reserve(all.size());
        for (const auto k : all) pts.push_back(xy(cloud, k));
        Piece joined;
        joined.threshold_m = threshold;
        if (!wallFromLine(totalLeastSquaresLine(pts), std::move(all), joined.wall)) continue;
        pieces[i] = std::move(joined);
        pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(j));
        merged = true;
      }
  }
}

}  // namespace

void WallConfig::validate() const {
  segmentation.validate();
  line.validate();
  if (!(threshold_per_m2 >= 0.0) || !std::isfinite(threshold_per_m2))
    throw std::invalid_argument("WallConfig.threshold_per_m2: must be >= 0");
  if (min_points < 2) throw std::invalid_argument("WallConfig.min_points: must be >= 2");
  if (!(min_inlier_fraction > 0.0 && min_inlier_fraction <= 1.0))
    throw std::invalid_argument("WallConfig.min_inlier_fraction: must be in (0, 1]");
  if (!(min_length_m >= 0.0)) throw std::invalid_argument("WallConfig.min_length_m: must be >= 0");
  if (!(merge_angle_rad >= 0.0 && merge_angle_rad < 0.5))
    throw std::invalid_argument("WallConfig.merge_angle_rad: must be in [0, 0.5)");
}

std::vector<Wall> findWalls(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                            const WallConfig& config) {
  config.validate();
  std::vector<Piece> pieces;
  for (const pcl::Indices& cluster : segmentScan(cloud, config.segmentation))
    splitIntoWalls(cloud, finitePoints(cloud, cluster), config, pieces);
  mergeCollinear(cloud, config, pieces);
  dropSharedPoints(cloud, pieces);
  std::vector<Wall> walls;
  walls.reserve(pieces.size());
  for (auto& p : pieces)
    if (static_cast<int>(p.wall.inliers.size()) >= config.min_points)
      walls.push_back(std::move(p.wall));
  std::sort(walls.begin(), walls.end(), [](const Wall& a, const Wall& b) {
    return a.normal_rad != b.normal_rad ? a.normal_rad < b.normal_rad : a.distance_m < b.distance_m;
  });
  return walls;
}

void RunWallConfig::validate() const {
  if (!(max_deviation_m > 0.0))
    throw std::invalid_argument("RunWallConfig.max_deviation_m: must be > 0");
  if (min_points < 2) throw std::invalid_argument("RunWallConfig.min_points: must be >= 2");
}

std::vector<Wall> findWallsInRun(const std::vector<Eigen::Vector2d>& run,
                                 const RunWallConfig& config) {
  config.validate();
  std::vector<Wall> walls;
  const auto min_points = static_cast<std::size_t>(config.min_points);
  const bool trim = config.drop_run_ends && run.size() >= 3;
  const std::size_t first = trim ? 1 : 0, last = trim ? run.size() - 1 : run.size();
  if (last - first < min_points) return walls;
  // pieces [lo, hi) still to check
  std::vector<std::pair<std::size_t, std::size_t>> stack{{first, last}};
  while (!stack.empty()) {
    const auto [lo, hi] = stack.back();
    stack.pop_back();
    if (hi - lo < min_points) continue;
    const std::vector<Eigen::Vector2d> pts(run.begin() + static_cast<long>(lo),
                                           run.begin() + static_cast<long>(hi));
    const Line2 line = totalLeastSquaresLine(pts);
    const NormalForm nf = normalForm(line);
    double worst = 0.0;
    std::size_t at = lo;
    for (std::size_t k = lo; k < hi; ++k) {
      const Eigen::Vector2d& q = pts[k - lo];
      const double dev = std::abs(q.x() * std::cos(nf.normal_rad) +
                                  q.y() * std::sin(nf.normal_rad) - nf.distance_m);
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
