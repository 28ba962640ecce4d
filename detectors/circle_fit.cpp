// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/circle_fit.hpp"
#include "detectors/ransac.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

namespace lidarcal::detectors {

const char* toString(FitStatus status) {
  switch (status) {
    case FitStatus::ok:
      return "ok";
    case FitStatus::too_few_points:
      return "too_few_points";
    case FitStatus::degenerate:
      return "degenerate";
    case FitStatus::no_consensus:
      return "no_consensus";
    case FitStatus::radius_out_of_limits:
      return "radius_out_of_limits";
    case FitStatus::wrong_side:
      return "wrong_side";
  }
  return "unknown";
}

void CircleFitConfig::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("CircleFitConfig.") + field + ": " + what);
  };
  if (!(inlier_threshold_m > 0.0) || !std::isfinite(inlier_threshold_m))
    fail("inlier_threshold_m", "must be > 0");
  // Both limits finite: PCL ignores the limits unless both differ from its +-max defaults.
  if (!(radius_min_m >= 0.0) || !std::isfinite(radius_min_m))
    fail("radius_min_m", "must be finite and >= 0");
  if (!(radius_max_m > radius_min_m) || !std::isfinite(radius_max_m))
    fail("radius_max_m", "must be finite and > radius_min_m");
  if (fixed_radius_m && !(*fixed_radius_m > 0.0 && std::isfinite(*fixed_radius_m)))
    fail("fixed_radius_m", "must be > 0");
  if (ransac_min_points < 3) fail("ransac_min_points", "must be >= 3");
  if (max_iterations < 1) fail("max_iterations", "must be >= 1");
  if (!(probability > 0.0 && probability < 1.0)) fail("probability", "must be in (0, 1)");
  if (refine_iterations < 1) fail("refine_iterations", "must be >= 1");
}

double circleRms(const std::vector<Eigen::Vector2d>& points, const Circle2& c) {
  if (points.empty()) return 0.0;
  double s = 0.0;
  for (const auto& p : points) {
    const double r = std::hypot(p.x() - c.x_m, p.y() - c.y_m) - c.radius_m;
    s += r * r;
  }
  return std::sqrt(s / static_cast<double>(points.size()));
}

std::optional<Circle2> taubinCircle(const std::vector<Eigen::Vector2d>& points) {
  const std::size_t n = points.size();
  if (n < 3) return std::nullopt;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(n);
  // Moments of the centred points, z = x^2 + y^2 (Taubin's normalisation by the mean of z).
  double mxx = 0, myy = 0, mxy = 0, mxz = 0, myz = 0, mzz = 0;
  for (const auto& p : points) {
    const double x = p.x() - mean.x(), y = p.y() - mean.y(), z = x * x + y * y;
    mxx += x * x, myy += y * y, mxy += x * y, mxz += x * z, myz += y * z, mzz += z * z;
  }
  const double inv = 1.0 / static_cast<double>(n);
  mxx *= inv, myy *= inv, mxy *= inv, mxz *= inv, myz *= inv, mzz *= inv;
  const double mz = mxx + myy;
  if (!(mz > 0.0)) return std::nullopt;
  const double cov_xy = mxx * myy - mxy * mxy;
  const double var_z = mzz - mz * mz;
  // Characteristic polynomial a3 x^3 + a2 x^2 + a1 x + a0; its smallest root from x = 0 by Newton.
  const double a3 = 4.0 * mz;
  const double a2 = -3.0 * mz * mz - mzz;
  const double a1 = var_z * mz + 4.0 * cov_xy * mz - mxz * mxz - myz * myz;
  const double a0 = mxz * (mxz * myy - myz * mxy) + myz * (myz * mxx - mxz * mxy) - var_z * cov_xy;
  double x = 0.0, y = a0;
  for (int it = 0; it < 100; ++it) {
    const double dy = a1 + x * (2.0 * a2 + 3.0 * a3 * x);
    if (dy == 0.0) break;
    const double x_new = x - y / dy;
    if (x_new == x || !std::isfinite(x_new)) break;
    const double y_new = a0 + x_new * (a1 + x_new * (a2 + x_new * a3));
    if (std::abs(y_new) >= std::abs(y)) break;
    x = x_new, y = y_new;
  }
  const double det = x * x - x * mz + cov_xy;
  // A vanishing determinant means the points lie on a line (infinite radius).
  if (!(std::abs(det) > 1e-14 * mz * mz)) return std::nullopt;
  const double cx = (mxz * (myy - x) - myz * mxy) / det / 2.0;
  const double cy = (myz * (mxx - x) - mxz * mxy) / det / 2.0;
  const Circle2 c{cx + mean.x(), cy + mean.y(), std::sqrt(cx * cx + cy * cy + mz)};
  if (!std::isfinite(c.x_m) || !std::isfinite(c.y_m) || !std::isfinite(c.radius_m))
    return std::nullopt;
  return c;
}

GeometricFit refineCircle(const std::vector<Eigen::Vector2d>& points, const Circle2& start,
                          std::optional<double> fixed_radius_m, int max_iterations) {
  const bool fixed = fixed_radius_m.has_value();
  const int m = fixed ? 2 : 3;
  Eigen::Vector3d theta(start.x_m, start.y_m, fixed ? *fixed_radius_m : start.radius_m);
  auto cost = [&](const Eigen::Vector3d& t) {
    double s = 0.0;
    for (const auto& p : points) {
      const double r = std::hypot(p.x() - t[0], p.y() - t[1]) - t[2];
      s += r * r;
    }
    return s;
  };
  GeometricFit out;
  double lambda = 1e-3;
  double current = cost(theta);
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    // Normal equations of the residuals r_i = |p_i - c| - r (Levenberg-Marquardt damping).
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (const auto& p : points) {
      const double dx = p.x() - theta[0], dy = p.y() - theta[1];
      const double d = std::max(std::hypot(dx, dy), 1e-300);
      const Eigen::Vector3d j(-dx / d, -dy / d, -1.0);
      const double r = d - theta[2];
      jtj += j * j.transpose();
      jtr += j * r;
    }
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::Matrix3d a = jtj.topLeftCorner(3, 3);
      for (int k = 0; k < m; ++k) a(k, k) += lambda * std::max(jtj(k, k), 1e-12);
      Eigen::Vector3d step = Eigen::Vector3d::Zero();
      step.head(m) = a.topLeftCorner(m, m).ldlt().solve(-jtr.head(m));
      const Eigen::Vector3d candidate = theta + step;
      const double c = cost(candidate);
      if (std::isfinite(c) && c <= current) {
        const bool negligible = step.norm() <= 1e-12 * (1.0 + theta.norm());
        theta = candidate;
        current = c;
        lambda = std::max(lambda * 0.1, 1e-12);
        improved = true;
        if (negligible) out.converged = true;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) out.converged = true;  // no step lowers the cost: at a minimum (to round-off)
    if (out.converged) break;
  }
  out.circle = Circle2{theta[0], theta[1], theta[2]};
  {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    for (const auto& p : points) {
      const double dx = p.x() - theta[0], dy = p.y() - theta[1];
      const double d = std::max(std::hypot(dx, dy), 1e-300);
      const Eigen::Vector3d j(-dx / d, -dy / d, -1.0);
      jtj += j * j.transpose();
    }
    const Eigen::MatrixXd block = jtj.topLeftCorner(m, m);
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(block);
    out.sensitivity.setConstant(std::numeric_limits<double>::infinity());
    if (fixed) out.sensitivity[2] = 0.0;
    if (lu.rank() == m) {
      const Eigen::MatrixXd inv = lu.inverse();
      for (int k = 0; k < m; ++k) out.sensitivity[k] = std::sqrt(std::max(inv(k, k), 0.0));
    }
  }
  out.rms_m = points.empty() ? 0.0 : std::sqrt(current / static_cast<double>(points.size()));
  return out;
}

namespace {

template <typename PointT>
void gather(const pcl::PointCloud<PointT>& cloud, const pcl::Indices& indices,
            std::vector<Eigen::Vector2d>& pts, pcl::Indices& idx) {
  pts.reserve(indices.size());
  idx.reserve(indices.size());
  for (const auto i : indices) {
    if (i < 0 || static_cast<std::size_t>(i) >= cloud.size())
      throw std::out_of_range("fitCircle: index outside the cloud");
    const auto& p = cloud[static_cast<std::size_t>(i)];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    pts.emplace_back(p.x, p.y);
    idx.push_back(i);
  }
}

std::size_t distinctCount(std::vector<Eigen::Vector2d> pts) {
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  return static_cast<std::size_t>(std::unique(pts.begin(), pts.end()) - pts.begin());
}

/// True when the points lie on a line to round-off (smallest/largest scatter eigenvalue).
bool collinear(const std::vector<Eigen::Vector2d>& pts) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  for (const auto& p : pts) s += (p - mean) * (p - mean).transpose();
  const Eigen::Vector2d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(s).eigenvalues();
  return !(ev[0] > 1e-12 * ev[1]);
}

std::vector<Eigen::Vector2d> subset(const std::vector<Eigen::Vector2d>& pts,
                                    const std::vector<std::size_t>& sel) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(sel.size());
  for (auto k : sel) out.push_back(pts[k]);
  return out;
}

bool withinLimits(const Circle2& c, const CircleFitConfig& cfg) {
  return c.radius_m >= cfg.radius_min_m && c.radius_m <= cfg.radius_max_m;
}

/// PCL RANSAC on the centred points; returns the consensus set (positions in pts) and model.
bool ransacCircle(const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector2d& origin,
                  const CircleFitConfig& cfg, std::vector<std::size_t>& consensus, Circle2& model) {
  // A deliberate small copy: PCL's minimal-sample solver works on float points, which we centre
  // so that metres of offset from the sensor do not eat the float mantissa.
  pcl::PointCloud<pcl::PointXYZ>::Ptr centred(new pcl::PointCloud<pcl::PointXYZ>);
  centred->reserve(pts.size());
  for (const auto& p : pts)
    centred->push_back(pcl::PointXYZ(static_cast<float>(p.x() - origin.x()),
                                     static_cast<float>(p.y() - origin.y()), 0.0f));
  pcl::Indices inliers;
  Eigen::VectorXf coefficients;
  const RansacSettings settings{cfg.inlier_threshold_m, cfg.max_iterations, cfg.probability};
  if (!ransacCircle2D(centred, settings, cfg.radius_min_m, cfg.radius_max_m, inliers,
                      coefficients) ||
      inliers.size() < 3 || coefficients.size() != 3)
    return false;
  consensus.assign(inliers.begin(), inliers.end());
  model = Circle2{coefficients[0] + origin.x(), coefficients[1] + origin.y(), coefficients[2]};
  return true;
}

/// Refuses fewer than 3 points, fewer than 3 distinct ones, or collinear ones. True when refused.
bool refuseDegenerate(const std::vector<Eigen::Vector2d>& pts, CircleFit& out) {
  if (pts.size() < 3) {
    out.status = out.free_status = FitStatus::too_few_points;
    out.message = "a circle needs at least 3 finite points, got " + std::to_string(pts.size());
    return true;
  }
  if (distinctCount(pts) < 3) {
    out.status = out.free_status = FitStatus::degenerate;
    out.message = "fewer than 3 distinct points (duplicates)";
    return true;
  }
  if (collinear(pts)) {
    out.status = out.free_status = FitStatus::degenerate;
    out.message = "the points are collinear";
    return true;
  }
  return false;
}

/// Free-radius fit of `sub`: Taubin start, geometric refinement; falls back to RANSAC's own model
/// when the refinement leaves the radius limits.
void fitFreeRadius(const std::vector<Eigen::Vector2d>& sub,
                   const std::optional<Circle2>& ransac_model, const CircleFitConfig& cfg,
                   CircleFit& out) {
  out.free_status = FitStatus::degenerate;
  if (const auto start = taubinCircle(sub)) {
    const GeometricFit g = refineCircle(sub, *start, std::nullopt, cfg.refine_iterations);
    out.free_circle = g.circle;
    out.free_radius_sensitivity = g.sensitivity[2];
    out.free_status = FitStatus::ok;
    out.iterations = g.iterations;
    if (!withinLimits(g.circle, cfg)) {
      if (ransac_model && withinLimits(*ransac_model, cfg)) {
        out.free_circle = *ransac_model;
        out.refinement_rejected = true;
      } else {
        out.free_status = FitStatus::radius_out_of_limits;
      }
    }
  }
  out.free_rms_m = circleRms(sub, out.free_circle);
}

/// Fixed-radius fit of `sub` (cfg.fixed_radius_m), from behind the arc along the line of sight,
/// else from the free fit, else from the centroid of all points.
void fitFixedRadius(const std::vector<Eigen::Vector2d>& sub, const Eigen::Vector2d& centroid,
                    const CircleFitConfig& cfg, CircleFit& out) {
  Circle2 start{centroid.x(), centroid.y(), *cfg.fixed_radius_m};
  Eigen::Vector2d m = Eigen::Vector2d::Zero();
  for (const auto& p : sub) m += p;
  m /= static_cast<double>(sub.size());
  if (cfg.seen_from) {
    // Start behind the arc, one radius beyond its mean along the line of sight.
    const Eigen::Vector2d dir = (m - *cfg.seen_from).normalized();
    start.x_m = m.x() + *cfg.fixed_radius_m * dir.x();
    start.y_m = m.y() + *cfg.fixed_radius_m * dir.y();
  } else if (out.free_status == FitStatus::ok) {
    start.x_m = out.free_circle.x_m, start.y_m = out.free_circle.y_m;
  }
  const GeometricFit g = refineCircle(sub, start, cfg.fixed_radius_m, cfg.refine_iterations);
  out.circle = g.circle;
  out.iterations = g.iterations;
}

/// Both fits on the points `sel`.
void fitSelection(const std::vector<Eigen::Vector2d>& pts, const std::vector<std::size_t>& sel,
                  const Eigen::Vector2d& centroid, const std::optional<Circle2>& ransac_model,
                  const CircleFitConfig& cfg, CircleFit& out) {
  const auto sub = subset(pts, sel);
  fitFreeRadius(sub, ransac_model, cfg, out);
  if (cfg.fixed_radius_m)
    fitFixedRadius(sub, centroid, cfg, out);
  else
    out.circle = out.free_circle;
  out.rms_m = circleRms(sub, out.circle);
}

/// Indices of the points within the inlier threshold of `c`.
std::vector<std::size_t> pointsOn(const std::vector<Eigen::Vector2d>& pts, const Circle2& c,
                                  double threshold_m) {
  std::vector<std::size_t> on;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const double r = std::hypot(pts[k].x() - c.x_m, pts[k].y() - c.y_m) - c.radius_m;
    if (std::abs(r) <= threshold_m) on.push_back(k);
  }
  return on;
}

/// Whether the centre lies in front of the arc `sel` seen from `from` (a concave surface).
bool concave(const std::vector<Eigen::Vector2d>& pts, const std::vector<std::size_t>& sel,
             const Circle2& circle, const Eigen::Vector2d& from) {
  Eigen::Vector2d m = Eigen::Vector2d::Zero();
  for (auto k : sel) m += pts[k];
  m /= static_cast<double>(sel.size());
  const Eigen::Vector2d c(circle.x_m, circle.y_m);
  return (c - from).norm() <= (m - from).norm();
}

CircleFit fitPoints(const std::vector<Eigen::Vector2d>& pts, const pcl::Indices& idx,
                    const CircleFitConfig& cfg) {
  cfg.validate();
  CircleFit out;
  if (refuseDegenerate(pts, out)) return out;
  const std::size_t n = pts.size();
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : pts) centroid += p;
  centroid /= static_cast<double>(n);

  // 1. Consensus set: PCL RANSAC from ransac_min_points on, else all points.
  std::vector<std::size_t> sel(n);
  for (std::size_t k = 0; k < n; ++k) sel[k] = k;
  std::optional<Circle2> ransac_model;
  if (static_cast<int>(n) >= cfg.ransac_min_points) {
    std::vector<std::size_t> consensus;
    Circle2 model;
    if (ransacCircle(pts, centroid, cfg, consensus, model)) {
      sel = std::move(consensus);
      ransac_model = model;
      out.used_ransac = true;
    } else if (!cfg.fixed_radius_m) {
      out.status = out.free_status = FitStatus::no_consensus;
      out.message = "RANSAC found no circle with radius in [" + std::to_string(cfg.radius_min_m) +
                    ", " + std::to_string(cfg.radius_max_m) + "] m";
      return out;
    }
  }

  // 2. Free- (and fixed-) radius fit on the consensus set.
  fitSelection(pts, sel, centroid, ransac_model, cfg, out);
  if (!cfg.fixed_radius_m && out.free_status != FitStatus::ok) {
    out.status = out.free_status;
    out.message = out.free_status == FitStatus::radius_out_of_limits
                      ? "best circle radius " + std::to_string(out.free_circle.radius_m) +
                            " m is outside [" + std::to_string(cfg.radius_min_m) + ", " +
                            std::to_string(cfg.radius_max_m) + "] m"
                      : "no circle through the consensus points (collinear)";
    return out;
  }

  // 3. Inliers of the refined circle among all points; refit once if the set grew. Never let the
  //    refined model shrink the consensus set (PCL's zero-inlier trap).
  std::vector<std::size_t> again = pointsOn(pts, out.circle, cfg.inlier_threshold_m);
  if (again.size() > sel.size()) {
    sel = std::move(again);
    fitSelection(pts, sel, centroid, ransac_model, cfg, out);
  }
  // The inliers in the order of `idx`: a scan's cluster runs in beam order, continuing across the
  // scan's end (beams n-1 | 0), so the first and last inliers are the arc's edges there too.
  std::vector<std::size_t> along = sel;
  std::sort(along.begin(), along.end());
  out.inliers.reserve(along.size());
  for (auto k : along) out.inliers.push_back(idx[k]);

  if (cfg.seen_from && concave(pts, sel, out.circle, *cfg.seen_from)) {
    out.status = FitStatus::wrong_side;
    out.message = "the circle's centre lies in front of the arc (a concave surface)";
    return out;
  }
  out.status = FitStatus::ok;
  return out;
}

template <typename PointT>
CircleFit fitCloud(const pcl::PointCloud<PointT>& cloud, const pcl::Indices& indices,
                   const CircleFitConfig& cfg) {
  std::vector<Eigen::Vector2d> pts;
  pcl::Indices idx;
  gather(cloud, indices, pts, idx);
  return fitPoints(pts, idx, cfg);
}

}  // namespace

CircleFit fitCircle(const pcl::PointCloud<pcl::PointXYZ>& cloud, const pcl::Indices& indices,
                    const CircleFitConfig& config) {
  return fitCloud(cloud, indices, config);
}

CircleFit fitCircle(const pcl::PointCloud<pcl::PointXYZI>& cloud, const pcl::Indices& indices,
                    const CircleFitConfig& config) {
  return fitCloud(cloud, indices, config);
}

}  // namespace lidarcal::detectors
