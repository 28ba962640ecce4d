// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/line_fit.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

#include "detectors/ransac.hpp"

namespace lidarcal::detectors {

void LineFitConfig::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("LineFitConfig.") + field + ": " + what);
  };
  if (!(inlier_threshold_m > 0.0) || !std::isfinite(inlier_threshold_m))
    fail("inlier_threshold_m", "must be > 0");
  if (ransac_min_points < 2) fail("ransac_min_points", "must be >= 2");
  if (max_iterations < 1) fail("max_iterations", "must be >= 1");
  if (!(probability > 0.0 && probability < 1.0)) fail("probability", "must be in (0, 1)");
}

Line2 totalLeastSquaresLine(const std::vector<Eigen::Vector2d>& points) {
  Line2 line;
  if (points.empty()) return line;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  for (const auto& p : points) s += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s);
  line.point = mean;
  line.direction = eig.eigenvectors().col(1).normalized();  // largest scatter
  line.normal = eig.eigenvectors().col(0);                  // smallest scatter
  line.rms_m = std::sqrt(std::max(eig.eigenvalues()[0], 0.0) / static_cast<double>(points.size()));
  return line;
}

NormalForm normalForm(const Line2& line) {
  Eigen::Vector2d n = line.normal;
  double p = n.dot(line.point);
  if (p < 0) {
    n = -n;
    p = -p;
  }
  return {std::atan2(n.y(), n.x()), p};
}

LineFit fitLine(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& indices,
                const LineFitConfig& cfg) {
  cfg.validate();
  LineFit out;
  std::vector<Eigen::Vector2d> pts;
  pcl::Indices idx;
  pts.reserve(indices.size());
  idx.reserve(indices.size());
  for (const auto i : indices) {
    if (i < 0 || static_cast<std::size_t>(i) >= cloud.size())
      throw std::out_of_range("fitLine: index outside the cloud");
    const auto& p = cloud[static_cast<std::size_t>(i)];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    pts.emplace_back(p.x, p.y);
    idx.push_back(i);
  }
  if (pts.size() < 2) {
    out.message = "a line needs at least 2 finite points, got " + std::to_string(pts.size());
    return out;
  }
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : pts) centroid += p;
  centroid /= static_cast<double>(pts.size());
  if ((pts.front() - pts.back()).norm() == 0.0 &&
      std::all_of(pts.begin(), pts.end(), [&](const auto& p) { return p == pts.front(); })) {
    out.status = FitStatus::degenerate;
    out.message = "all points coincide";
    return out;
  }

  std::vector<std::size_t> sel(pts.size());
  for (std::size_t k = 0; k < pts.size(); ++k) sel[k] = k;
  if (static_cast<int>(pts.size()) >= cfg.ransac_min_points) {
    // Deliberate small copy, centred for float precision (see circle_fit.hpp).
    pcl::PointCloud<pcl::PointXYZ>::Ptr centred(new pcl::PointCloud<pcl::PointXYZ>);
    centred->reserve(pts.size());
    for (const auto& p : pts)
      centred->push_back(pcl::PointXYZ(static_cast<float>(p.x() - centroid.x()),
                                       static_cast<float>(p.y() - centroid.y()), 0.0f));
    pcl::Indices inliers;
    Eigen::VectorXf coefficients;
    const RansacSettings settings{cfg.inlier_threshold_m, cfg.max_iterations, cfg.probability};
    ransacLine(centred, settings, inliers, coefficients);
    if (inliers.size() < 2) {
      out.status = FitStatus::no_consensus;
      out.message = "RANSAC found no line";
      return out;
    }
    sel.assign(inliers.begin(), inliers.end());
    out.used_ransac = true;
  }
  std::vector<Eigen::Vector2d> sub;
  sub.reserve(sel.size());
  for (auto k : sel) sub.push_back(pts[k]);
  out.line = totalLeastSquaresLine(sub);
  for (auto k : sel) out.inliers.push_back(idx[k]);
  std::sort(out.inliers.begin(), out.inliers.end());
  out.status = FitStatus::ok;
  return out;
}

}  // namespace lidarcal::detectors
