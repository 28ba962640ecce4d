// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/scan_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/pose2.hpp"
#include "common/stats_util.hpp"
#include "detectors/line_fit.hpp"

namespace lidarcal::detectors {

const char* toString(ClusterKind kind) {
  switch (kind) {
    case ClusterKind::circle:
      return "circle";
    case ClusterKind::line:
      return "line";
    case ClusterKind::clutter:
      return "clutter";
  }
  return "unknown";
}

void DetectionConfig::validate() const {
  auto fail = [](const char* field, const char* what) {
    throw std::invalid_argument(std::string("DetectionConfig.") + field + ": " + what);
  };
  segmentation.validate();
  if (landmark_radius_m && !(*landmark_radius_m > 0.0 && std::isfinite(*landmark_radius_m)))
    fail("landmark_radius_m", "must be > 0");
  if (!(radius_min_m > 0.0) || !std::isfinite(radius_min_m)) fail("radius_min_m", "must be > 0");
  if (!(radius_max_m > radius_min_m) || !std::isfinite(radius_max_m))
    fail("radius_max_m", "must be > radius_min_m");
  if (!(known_radius_min_factor > 0.0 && known_radius_min_factor < 1.0))
    fail("known_radius_min_factor", "must be in (0, 1)");
  if (!(known_radius_max_factor > 1.0) || !std::isfinite(known_radius_max_factor))
    fail("known_radius_max_factor", "must be > 1");
  if (min_points < 3) fail("min_points", "must be >= 3");
  if (min_points_free < 4) fail("min_points_free", "must be >= 4");
  if (!(threshold_m > 0.0) || !std::isfinite(threshold_m)) fail("threshold_m", "must be > 0");
  if (!(threshold_per_m2 >= 0.0) || !std::isfinite(threshold_per_m2))
    fail("threshold_per_m2", "must be >= 0");
  if (!(max_rms_fraction > 0.0) || !std::isfinite(max_rms_fraction))
    fail("max_rms_fraction", "must be > 0");
  if (!(min_inlier_fraction > 0.0 && min_inlier_fraction <= 1.0))
    fail("min_inlier_fraction", "must be in (0, 1]");
  if (!(extent_factor >= 1.0) || !std::isfinite(extent_factor))
    fail("extent_factor", "must be >= 1");
  if (!(min_width_fraction >= 0.0 && min_width_fraction <= 1.0))
    fail("min_width_fraction", "must be in [0, 1]");
  if (!(line_evidence >= 0.0) || !std::isfinite(line_evidence))
    fail("line_evidence", "must be >= 0");
  if (!(line_rms_ratio >= 0.0) || !std::isfinite(line_rms_ratio))
    fail("line_rms_ratio", "must be >= 0");
  if (!(max_threshold_to_radius > 0.0) || !std::isfinite(max_threshold_to_radius))
    fail("max_threshold_to_radius", "must be > 0");
  if (!(max_radius_uncertainty > 0.0)) fail("max_radius_uncertainty", "must be > 0");
  if (free_radius_check_points < 3) fail("free_radius_check_points", "must be >= 3");
  if (max_iterations < 1) fail("max_iterations", "must be >= 1");
  if (ransac_min_points < 3) fail("ransac_min_points", "must be >= 3");
  for (const auto& h : radius_hints)
    if (!(h.radius_m > 0.0) || !std::isfinite(h.x_m) || !std::isfinite(h.y_m))
      fail("radius_hints", "need finite positions and radius > 0");
  if (!(hint_distance_m > 0.0) || !std::isfinite(hint_distance_m))
    fail("hint_distance_m", "must be > 0");
}

void setCentre(Detection& d, const Circle2& c) {
  d.centre_x_m = c.x_m;
  d.centre_y_m = c.y_m;
  d.radius_m = c.radius_m;
  d.bearing_rad = std::atan2(c.y_m, c.x_m);
  d.range_m = std::hypot(c.x_m, c.y_m);
}

namespace {

/// Angular span of points seen from the sensor, radians (bearings relative to `reference_rad`).
double angularSpan(const std::vector<Eigen::Vector2d>& pts, double reference_rad) {
  double lo = 0.0, hi = 0.0;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const double a = wrapAngle(std::atan2(pts[k].y(), pts[k].x()) - reference_rad);
    if (k == 0 || a < lo) lo = a;
    if (k == 0 || a > hi) hi = a;
  }
  return hi - lo;
}

/// Smallest sum of squared perpendicular distances of two lines through the points split in
/// two runs (each of at least 3 points): a corner. Infinity for fewer than 6 points. Prefix sums
/// of the moments make it linear in the number of points.
double cornerSumSquares(const std::vector<Eigen::Vector2d>& ordered) {
  const std::size_t n = ordered.size();
  if (n < 6) return std::numeric_limits<double>::infinity();
  Eigen::Vector2d origin = ordered.front();
  std::vector<Eigen::Matrix<double, 6, 1>> prefix(n + 1, Eigen::Matrix<double, 6, 1>::Zero());
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d p = ordered[k] - origin;
    Eigen::Matrix<double, 6, 1> m;
    m << 1.0, p.x(), p.y(), p.x() * p.x(), p.x() * p.y(), p.y() * p.y();
    prefix[k + 1] = prefix[k] + m;
  }
  auto ss = [&](std::size_t a, std::size_t b) {  // points [a, b)
    const Eigen::Matrix<double, 6, 1> m = prefix[b] - prefix[a];
    const double c = m[0], mx = m[1] / c, my = m[2] / c;
    const double sxx = m[3] - c * mx * mx, sxy = m[4] - c * mx * my, syy = m[5] - c * my * my;
    // Smallest eigenvalue of the 2x2 scatter matrix.
    const double tr = sxx + syy, det = sxx * syy - sxy * sxy;
    return std::max(0.0, 0.5 * tr - std::sqrt(std::max(0.0, 0.25 * tr * tr - det)));
  };
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 3; k + 3 <= n; ++k) best = std::min(best, ss(0, k) + ss(k, n));
  return best;
}

struct Classifier {
  const pcl::PointCloud<pcl::PointXYZI>& cloud;
  const DetectionConfig& cfg;
  double angular_step_rad;

  /// True when the beam next to `end` (towards `step`) has a return nearer than `end`: the cluster
  /// is cut by something in front of it (a wall seen between chair legs, a partly hidden pole).
  bool nearerNeighbour(int end, int step) const {
    const int n = static_cast<int>(cloud.size());
    const auto& e = cloud[static_cast<std::size_t>(end)];
    const auto& b = cloud[static_cast<std::size_t>(((end + step) % n + n) % n)];
    if (!std::isfinite(b.x) || !std::isfinite(b.y)) return false;
    return std::hypot(b.x, b.y) < std::hypot(e.x, e.y);
  }

  /// Radius of the hinted landmark nearest the cluster (its mean point lies about one radius in
  /// front of the centre), when one is within hint_distance_m.
  std::optional<double> hintedRadius(const std::vector<Eigen::Vector2d>& pts) const {
    if (cfg.radius_hints.empty()) return std::nullopt;
    Eigen::Vector2d m = Eigen::Vector2d::Zero();
    for (const auto& p : pts) m += p;
    m /= static_cast<double>(pts.size());
    std::optional<double> radius;
    double best = std::numeric_limits<double>::infinity();
    for (const auto& h : cfg.radius_hints) {
      const double d = std::abs((m - Eigen::Vector2d(h.x_m, h.y_m)).norm() - h.radius_m);
      if (d <= cfg.hint_distance_m && d < best) best = d, radius = h.radius_m;
    }
    return radius;
  }

  /// Line or clutter, with the reason the cluster is no circle.
  void notCircle(const pcl::Indices& idx, double t, ClusterSummary& s, std::string reason) const {
    s.reason = std::move(reason);
    s.kind = ClusterKind::clutter;
    if (idx.size() < 2) return;
    LineFitConfig lc;
    lc.inlier_threshold_m = t;
    lc.max_iterations = cfg.max_iterations;
    const LineFit line = fitLine(cloud, idx, lc);
    if (line.status == FitStatus::ok &&
        static_cast<double>(line.inliers.size()) >= 0.8 * static_cast<double>(idx.size()) &&
        line.line.rms_m <= cfg.max_rms_fraction * t)
      s.kind = ClusterKind::line;
  }

  /// What a cluster is held against: the noise threshold at its range and the radii a landmark
  /// may have there.
  struct Gates {
    double range = 0.0;  // upper median range of the points
    double t = 0.0;      // inlier threshold at that range
    std::optional<double> radius_known;
    double r_lo = 0.0, r_hi = 0.0, r_wide = 0.0;
    std::size_t min_points = 0;
  };

  Gates gates(const std::vector<Eigen::Vector2d>& pts) const {
    std::vector<double> ranges;
    ranges.reserve(pts.size());
    for (const auto& p : pts) ranges.push_back(p.norm());
    Gates g;
    g.range = upperMedian(std::move(ranges));
    g.t = cfg.threshold(g.range);
    g.radius_known = cfg.landmark_radius_m ? cfg.landmark_radius_m : hintedRadius(pts);
    const bool known = g.radius_known.has_value();
    g.r_lo = known ? *g.radius_known * cfg.known_radius_min_factor : cfg.radius_min_m;
    g.r_hi = known ? *g.radius_known * cfg.known_radius_max_factor : cfg.radius_max_m;
    g.min_points = static_cast<std::size_t>(known ? cfg.min_points : cfg.min_points_free);
    g.r_wide = known ? *g.radius_known : cfg.radius_max_m;
    return g;
  }

  /// True (with the reason in s) when the cluster is no landmark before any fit.
  bool rejectedBeforeFit(const pcl::Indices& idx, const std::vector<Eigen::Vector2d>& pts,
                         const Gates& g, ClusterSummary& s) const {
    if (idx.size() < g.min_points) {
      s.reason = "too few points (" + std::to_string(idx.size()) + ")";
      return true;
    }
    if (g.t > cfg.max_threshold_to_radius * g.r_wide) {
      s.reason = "too far: the noise hides the shape of a landmark";
      return true;
    }
    if (cfg.require_free_edges &&
        (nearerNeighbour(idx.front(), -1) || nearerNeighbour(idx.back(), +1))) {
      s.reason = "partly hidden (a neighbouring return is nearer)";
      return true;
    }
    // Width across the line of sight: bearings are exact while range noise moves points radially.
    const Eigen::Vector2d& mid_point = pts[pts.size() / 2];
    if (g.range * angularSpan(pts, std::atan2(mid_point.y(), mid_point.x())) >
        2.0 * g.r_wide * cfg.extent_factor) {
      notCircle(idx, g.t, s, "wider than a landmark");
      return true;
    }
    return false;
  }

  /// The circle fit and the checks on it; nullopt (with the reason in s) when it fails. Sets
  /// radius_stddev, the free radius's standard deviation.
  std::optional<CircleFit> fittedCircle(const pcl::Indices& idx, const Gates& g, ClusterSummary& s,
                                        double& radius_stddev) const {
    const bool known = g.radius_known.has_value();
    CircleFitConfig cc;
    cc.inlier_threshold_m = g.t;
    cc.radius_min_m = g.r_lo;
    cc.radius_max_m = g.r_hi;
    cc.fixed_radius_m = g.radius_known;
    cc.seen_from = Eigen::Vector2d::Zero();
    cc.ransac_min_points = cfg.ransac_min_points;
    cc.max_iterations = cfg.max_iterations;
    CircleFit fit = fitCircle(cloud, idx, cc);
    const double t = g.t;
    if (fit.status != FitStatus::ok) {
      notCircle(idx, t, s, std::string("circle fit: ") + toString(fit.status));
      return std::nullopt;
    }
    const std::size_t n_in = fit.inliers.size();
    if (n_in < g.min_points ||
        static_cast<double>(n_in) < cfg.min_inlier_fraction * static_cast<double>(idx.size())) {
      notCircle(idx, t, s, "too few points on the circle");
      return std::nullopt;
    }
    if (fit.rms_m > cfg.max_rms_fraction * t) {
      notCircle(idx, t, s, "circle fit too poor");
      return std::nullopt;
    }
    const double p_free =
        static_cast<double>(n_in) > 3.0 ? std::sqrt(double(n_in) / (double(n_in) - 3.0)) : 0.0;
    radius_stddev = fit.free_radius_sensitivity * std::max(fit.free_rms_m * p_free, t / 3.0);
    if (!known && !(radius_stddev <= cfg.max_radius_uncertainty * fit.free_circle.radius_m)) {
      notCircle(idx, t, s, "radius not determined by the arc");
      return std::nullopt;
    }
    if (known && static_cast<int>(n_in) >= cfg.free_radius_check_points &&
        fit.free_status != FitStatus::ok) {
      notCircle(idx, t, s,
                std::string("free radius disagrees with the landmark radius (") +
                    toString(fit.free_status) + ")");
      return std::nullopt;
    }
    return fit;
  }

  /// True (with the reason in s) when the circle's inliers are no pole after all: an arc
  /// narrower than a pole looks, or a line or a corner that explains them better.
  bool notAPole(const CircleFit& fit, const Gates& g, ClusterSummary& s) const {
    const std::size_t n_in = fit.inliers.size();
    std::vector<Eigen::Vector2d> in;
    in.reserve(n_in);
    for (auto i : fit.inliers)
      in.emplace_back(cloud[static_cast<std::size_t>(i)].x, cloud[static_cast<std::size_t>(i)].y);
    // The arc must be as wide as a pole of this radius looks from here (chair legs and edges of
    // partly hidden objects are narrower); the end points lie up to one beam inside the edges.
    const double radius = fit.circle.radius_m;
    const double dist = std::hypot(fit.circle.x_m, fit.circle.y_m);
    const double bearing = std::atan2(fit.circle.y_m, fit.circle.x_m);
    const double width = 2.0 * std::asin(std::min(1.0, radius / dist));
    if (angularSpan(in, bearing) < cfg.min_width_fraction * width - 2.0 * angular_step_rad) {
      s.reason = "arc narrower than a landmark";
      return true;
    }
    // Neither a straight line (a wall, a box face) nor two straight faces meeting at a corner (a
    // box) may explain the points clearly better: a lower sum of squares by more than
    // line_evidence noise variances (noise ~ t / 3) and a clearly lower RMS per degree of freedom.
    // Far poles seen by 3-4 beams are noise-dominated and stay circles.
    std::sort(in.begin(), in.end(), [&](const auto& a, const auto& b) {
      return wrapAngle(std::atan2(a.y(), a.x()) - bearing) <
             wrapAngle(std::atan2(b.y(), b.x()) - bearing);
    });
    const double n = static_cast<double>(n_in), p_circle = g.radius_known ? 2.0 : 3.0;
    const double ss_circle = n * fit.rms_m * fit.rms_m, sigma = g.t / 3.0;
    auto explainsBetter = [&](double ss, double params) {
      if (!(n > params) || !(n > p_circle)) return false;
      const double evidence = (ss_circle - ss) / (sigma * sigma);
      return evidence > cfg.line_evidence &&
             std::sqrt(ss / (n - params)) <
                 cfg.line_rms_ratio * std::sqrt(ss_circle / (n - p_circle));
    };
    const Line2 line = totalLeastSquaresLine(in);
    if (explainsBetter(n * line.rms_m * line.rms_m, 2.0)) {
      s.kind = ClusterKind::line;
      s.reason = "a line fits better";
      return true;
    }
    if (explainsBetter(cornerSumSquares(in), 5.0)) {
      s.kind = ClusterKind::line;
      s.reason = "two straight faces (a corner) fit better";
      return true;
    }
    return false;
  }

  std::optional<Detection> classify(const pcl::Indices& idx, ClusterSummary& s) const {
    std::vector<Eigen::Vector2d> pts;
    pts.reserve(idx.size());
    for (auto i : idx) {
      const auto& p = cloud[static_cast<std::size_t>(i)];
      pts.emplace_back(p.x, p.y);
    }
    const Gates g = gates(pts);
    if (rejectedBeforeFit(idx, pts, g, s)) return std::nullopt;
    double radius_stddev = 0.0;
    const std::optional<CircleFit> fit = fittedCircle(idx, g, s, radius_stddev);
    if (!fit || notAPole(*fit, g, s)) return std::nullopt;
    Detection d;
    setCentre(d, fit->circle);
    d.radius_fixed = g.radius_known.has_value();
    d.rms_m = fit->rms_m;
    d.free_status = fit->free_status;
    d.free_centre_x_m = fit->free_circle.x_m;
    d.free_centre_y_m = fit->free_circle.y_m;
    d.free_radius_m = fit->free_circle.radius_m;
    d.free_rms_m = fit->free_rms_m;
    d.free_radius_stddev_m = fit->free_status == FitStatus::ok ? radius_stddev : 0.0;
    d.cluster_points = idx.size();
    d.inliers = fit->inliers;
    s.kind = ClusterKind::circle;
    return d;
  }
};

}  // namespace

ScanDetections detectScan(const pcl::PointCloud<pcl::PointXYZI>& cloud,
                          const DetectionConfig& cfg) {
  cfg.validate();
  ScanDetections out;
  for (const auto& p : cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y)) ++out.returns;
  const Classifier classifier{cloud, cfg, estimateAngularStep(cloud)};
  const auto clusters = segmentScan(cloud, cfg.segmentation);
  out.clusters.reserve(clusters.size());
  std::vector<Detection> found;
  for (const auto& idx : clusters) {
    ClusterSummary s;
    s.first_index = idx.front();
    s.last_index = idx.back();
    s.points = idx.size();
    if (auto d = classifier.classify(idx, s)) found.push_back(std::move(*d));
    out.clusters.push_back(std::move(s));
  }
  // One pole, one detection: of two circles closer than their radius keep the better supported.
  std::stable_sort(found.begin(), found.end(), [](const Detection& a, const Detection& b) {
    return a.inliers.size() > b.inliers.size();
  });
  for (auto& d : found) {
    const bool duplicate =
        std::any_of(out.detections.begin(), out.detections.end(), [&](const Detection& k) {
          return std::hypot(k.centre_x_m - d.centre_x_m, k.centre_y_m - d.centre_y_m) <
                 std::max(k.radius_m, d.radius_m);
        });
    if (!duplicate) out.detections.push_back(std::move(d));
  }
  // Report in scan order of the first inlier.
  std::sort(
      out.detections.begin(), out.detections.end(),
      [](const Detection& a, const Detection& b) { return a.inliers.front() < b.inliers.front(); });
  return out;
}

ScanDetections detectScan(const io::Scan& scan, const DetectionConfig& config) {
  if (!scan.cloud) throw std::invalid_argument("detectScan: scan without a cloud");
  return detectScan(*scan.cloud, config);
}

}  // namespace lidarcal::detectors
