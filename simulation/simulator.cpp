// SPDX-License-Identifier: BSD-3-Clause
#include "simulation/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/rng.hpp"
#include "io/sequence.hpp"
#include "simulation/raycast.hpp"

namespace lidarcal::simulation {

double rangeReading(const RangeModel& model, double d_m, double unit_normal) {
  return model.bias(d_m) + model.noise.stddev(d_m, model.bias) * unit_normal;
}

std::mt19937_64 effectRng(std::uint64_t seed, std::size_t scan) {
  return makeRng(deriveSeed(seed, 0xEFFEC75ULL), static_cast<std::uint64_t>(scan) + 1);
}

double effectReading(const RangeModel& model, const RangeEffects& fx, double d_m,
                     const BeamContext& beam, double unit_normal, std::mt19937_64& effect_rng) {
  if (!fx.any() && beam.surface_offset_m == 0.0) return rangeReading(model, d_m, unit_normal);
  double e = unit_normal;
  if (fx.noise_student_dof > 0.0) {
    // t = z / sqrt(chi2_nu / nu), scaled to unit variance (nu > 2).
    std::chi_squared_distribution<double> chi2(fx.noise_student_dof);
    const double nu = fx.noise_student_dof;
    e = unit_normal / std::sqrt(chi2(effect_rng) / nu) * std::sqrt((nu - 2.0) / nu);
  }
  const double c = clampCosIncidence(beam.cos_incidence);
  const double sigma = model.noise.stddev(d_m, model.bias) *
                       incidenceNoiseFactor(fx.incidence_noise_exponent, c) *
                       darkNoiseFactor(fx.dark_noise_exponent,
                                       darkness(beam.intensity, fx.dark_reference_intensity));
  // The mean reading as the joint refinement models it (common/range_effects.hpp), with the
  // ripple no fit models.
  const double y = expectedReading(model.bias(d_m) + rangeRipple(fx, d_m), beam.surface_offset_m,
                                   fx.range_drift_m_per_scan,
                                   static_cast<double>(beam.scan) - fx.range_drift_reference_scan,
                                   fx.incidence_bias_m, c) +
                   sigma * e;
  return quantise(y, fx.range_resolution_m);
}

double mixedPixelDistance(const RangeEffects& fx, double d_m, double background_m,
                          std::mt19937_64& effect_rng) {
  if (fx.mixed_pixel_fraction <= 0.0) return d_m;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double u = unit(effect_rng), w = unit(effect_rng);
  if (!(background_m > d_m) || u >= fx.mixed_pixel_fraction) return d_m;
  return w * d_m + (1.0 - w) * background_m;
}

namespace {

/// Walks a route piece by piece (each an arc of constant curvature, or straight), looping.
class RouteWalker {
 public:
  explicit RouteWalker(const std::vector<RouteSegment>& route) : route_(route) {
    if (route_.empty())
      throw std::invalid_argument("planStops: a driving route needs at least one piece");
    for (const auto& r : route_)
      if (!(r.length_m > 0.0) || !std::isfinite(r.length_m) || !std::isfinite(r.turn_rad))
        throw std::invalid_argument(
            "planStops: route pieces need a finite length > 0 and a finite turn");
  }
  /// Moves `pose` forward by `distance_m` along the route.
  void advance(Pose2& pose, double distance_m) {
    while (distance_m > 0.0) {
      const RouteSegment& piece = route_[piece_];
      const double ds = std::min(distance_m, piece.length_m - done_m_);
      const double curvature = piece.turn_rad / piece.length_m;
      const double turn = curvature * ds;
      // Exact arc: chord (sin(turn), 1 - cos(turn)) / curvature; a straight step when it does not
      // turn.
      const Pose2 step = std::abs(turn) < 1e-12 ? Pose2{ds, 0.0, 0.0}
                                                : Pose2{std::sin(turn) / curvature,
                                                        (1.0 - std::cos(turn)) / curvature, turn};
      pose = compose(pose, step);
      done_m_ += ds;
      distance_m -= ds;
      if (done_m_ >= piece.length_m) {
        done_m_ = 0.0;
        piece_ = (piece_ + 1) % route_.size();
      }
    }
  }

 private:
  const std::vector<RouteSegment>& route_;
  std::size_t piece_ = 0;
  double done_m_ = 0.0;  // travelled on the current piece
};

/// A driving robot: the true poses every speed_m_per_scan along the route; the commanded ones
/// chain the odometry's noisy measurements of each true step (scene.hpp, OdometryNoise).
std::vector<TruthStop> planDriving(const Scene& scene, std::uint64_t seed) {
  const PathSpec& path = scene.path;
  const DrivingSpec& drive = path.driving;
  const OdometryNoise& odo = drive.odometry;
  if (!(drive.speed_m_per_scan > 0.0) || !std::isfinite(drive.speed_m_per_scan))
    throw std::invalid_argument("planStops: speed_m_per_scan must be > 0");
  auto rng = makeRng(seed, 0);
  std::normal_distribution<double> normal(0.0, 1.0);
  RouteWalker walker(drive.route);
  const double reported = 1.0 / (1.0 + path.step_error_fraction);  // odometry scale error
  Pose2 actual = path.start, commanded = path.start;
  std::vector<TruthStop> stops;
  stops.reserve(static_cast<std::size_t>(path.stops));
  for (int k = 0; k < path.stops; ++k) {
    if (k > 0) {
      Pose2 next = actual;
      walker.advance(next, drive.speed_m_per_scan);
      const Pose2 step = stepBetween(actual, next);
      const double s = std::hypot(step.x_m, step.y_m);
      const double e1 = normal(rng), e2 = normal(rng), e3 = normal(rng);
      const Pose2 measured{
          reported * step.x_m + odo.translation_fraction * s * e1,
          reported * step.y_m + odo.translation_fraction * s * e2,
          step.yaw_rad +
              (odo.heading_rad_per_m * s + odo.heading_fraction * std::abs(step.yaw_rad)) * e3};
      commanded = compose(commanded, measured);
      actual = next;
    }
    TruthStop t;
    t.commanded = commanded;
    t.actual = actual;
    t.first_scan = static_cast<std::size_t>(k) * static_cast<std::size_t>(path.scans_per_stop);
    t.scans = static_cast<std::size_t>(path.scans_per_stop);
    stops.push_back(t);
  }
  return stops;
}

}  // namespace

std::pair<double, double> poleDistanceRange(const Scene& scene,
                                            const std::vector<TruthStop>& stops) {
  const RangeModel& r = scene.sensor.range;
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const TruthStop& s : stops)
    for (const Cylinder& c : scene.landmarks) {
      const double d = std::hypot(c.x_m - s.actual.x_m, c.y_m - s.actual.y_m) - c.radius_m;
      if (d < r.range_min_m || d > r.range_max_m) continue;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  return lo <= hi ? std::make_pair(lo, hi) : std::make_pair(r.range_min_m, r.range_max_m);
}

std::vector<TruthStop> planStops(const Scene& scene, std::uint64_t seed) {
  if (scene.path.kind == PathKind::driving) return planDriving(scene, seed);
  auto rng = makeRng(seed, 0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<TruthStop> stops;
  stops.reserve(static_cast<std::size_t>(scene.path.stops));
  for (int k = 0; k < scene.path.stops; ++k) {
    TruthStop s;
    s.commanded = commandedPose(scene.path, k);
    s.actual = s.commanded;
    // An odometry scale error: the robot really moves (1 + e) times the commanded step.
    const double extra = k * scene.path.step_m * scene.path.step_error_fraction;
    s.actual.x_m += extra * std::cos(scene.path.start.yaw_rad);
    s.actual.y_m += extra * std::sin(scene.path.start.yaw_rad);
    // Eq. 8: the true position scatters around the commanded one, independently per stop.
    const double ex = normal(rng), ey = normal(rng), epsi = normal(rng);
    s.actual.x_m += scene.path.sigma_s_m * ex;
    s.actual.y_m += scene.path.sigma_s_m * ey;
    s.actual.yaw_rad = wrapAngle(s.actual.yaw_rad + scene.path.sigma_psi_rad * epsi);
    s.first_scan =
        static_cast<std::size_t>(k) * static_cast<std::size_t>(scene.path.scans_per_stop);
    s.scans = static_cast<std::size_t>(scene.path.scans_per_stop);
    stops.push_back(s);
  }
  return stops;
}

namespace {

/// Depth discontinuity: the nearest neighbour beam of `b` on another surface farther away is the
/// background (NaN: none).
double backgroundRange(const std::vector<RayHit>& hits, std::size_t b, bool full_circle) {
  const RayHit& hit = hits[b];
  const auto n = static_cast<long>(hits.size());
  double background = std::numeric_limits<double>::quiet_NaN();
  for (long step : {-1L, 1L}) {
    long j = static_cast<long>(b) + step;
    if (full_circle) j = (j + n) % n;
    if (j < 0 || j >= n) continue;
    const RayHit& nb = hits[static_cast<std::size_t>(j)];
    if (nb.kind == io::TargetKind::none || (nb.kind == hit.kind && nb.id == hit.id) ||
        nb.range_m <= hit.range_m)
      continue;
    if (std::isnan(background) || nb.range_m < background) background = nb.range_m;
  }
  return background;
}

/// The true range of a beam's hit, as the truth file records it.
io::TrueRange trueRange(const RayHit& hit, std::size_t scan_index, std::size_t b) {
  io::TrueRange t;
  t.scan = static_cast<std::uint32_t>(scan_index);
  t.beam = static_cast<std::uint32_t>(b);
  t.range_m =
      hit.kind == io::TargetKind::none ? std::numeric_limits<double>::quiet_NaN() : hit.range_m;
  t.target = hit.kind;
  t.target_id = hit.id;
  t.incidence_rad = hit.incidence_rad;
  return t;
}

}  // namespace

SimulatedScan simulateScan(const Scene& scene, const TruthStop& stop, std::size_t scan_index,
                           std::uint64_t seed) {
  const SensorSpec& sensor = scene.sensor;
  const RangeModel& model = sensor.range;
  const auto n = static_cast<std::size_t>(sensor.beams);
  auto rng = makeRng(seed, scan_index + 1);
  std::normal_distribution<double> normal(0.0, 1.0);

  SimulatedScan out;
  out.scan.name = io::scanFileName(scan_index);
  out.scan.viewpoint = stop.commanded;
  // An intensity field when a surface of the scene records one (the scans of scenes without stay as
  // they were).
  const auto bright = [](const auto& v) {
    return std::any_of(v.begin(), v.end(), [](const auto& s) { return s.intensity > 0.0; });
  };
  out.scan.has_intensity = bright(scene.landmarks) || bright(scene.clutter) || bright(scene.walls);
  out.scan.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  out.scan.cloud->resize(n);
  out.scan.cloud->width = static_cast<std::uint32_t>(n);
  out.scan.cloud->height = 1;
  out.scan.cloud->is_dense = true;
  out.truth.resize(n);

  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  // Cast every beam first (mixed pixels look at the neighbours), then read.
  std::vector<RayHit> hits(n);
  std::vector<double> unit_normal(n), beam_angle(n);
  for (std::size_t b = 0; b < n; ++b) {
    // Draw both numbers for every beam, hit or not, so streams stay aligned across scenes.
    const double jitter = normal(rng), e = normal(rng);
    const double beam_rad =
        sensor.angle_min_rad + static_cast<double>(b) * sensor.angle_increment_rad;
    const double world_rad =
        stop.actual.yaw_rad + sensor.mount_yaw_rad + beam_rad + sensor.bearing_noise_rad * jitter;
    const Ray ray{stop.actual.x_m, stop.actual.y_m, std::cos(world_rad), std::sin(world_rad)};
    hits[b] = castRay(scene, ray);
    unit_normal[b] = e;
    beam_angle[b] = beam_rad;
  }
  const bool full_circle =
      std::abs(static_cast<double>(n) * sensor.angle_increment_rad - 2.0 * kPi) < 1e-6;
  auto effect_rng = effectRng(seed, scan_index);
  for (std::size_t b = 0; b < n; ++b) {
    const RayHit& hit = hits[b];
    out.truth[b] = trueRange(hit, scan_index, b);

    auto& pt = (*out.scan.cloud)[b];
    pt.intensity = 0.0f;
    double reading = std::numeric_limits<double>::quiet_NaN();
    if (hit.kind != io::TargetKind::none) {
      const double background = backgroundRange(hits, b, full_circle);
      const double d = mixedPixelDistance(sensor.effects, hit.range_m, background, effect_rng);
      const BeamContext ctx{std::cos(hit.incidence_rad), surfaceOffset(scene, hit), scan_index,
                            surfaceIntensity(scene, hit)};
      pt.intensity = static_cast<float>(ctx.intensity);
      reading = effectReading(model, sensor.effects, d, ctx, unit_normal[b], effect_rng);
    }
    // The sensor reports only readings inside its window; anything else is a beam without return.
    if (!(reading >= model.range_min_m && reading <= model.range_max_m)) {
      pt.x = pt.y = pt.z = kNaN;
      out.scan.cloud->is_dense = false;
      continue;
    }
    pt.x = static_cast<float>(reading * std::cos(beam_angle[b]));
    pt.y = static_cast<float>(reading * std::sin(beam_angle[b]));
    pt.z = 0.0f;
  }
  return out;
}

void forEachScan(const Scene& scene, const std::vector<TruthStop>& stops, std::uint64_t seed,
                 const std::function<void(std::size_t stop, SimulatedScan&& scan)>& visit) {
  for (std::size_t k = 0; k < stops.size(); ++k)
    for (std::size_t i = 0; i < stops[k].scans; ++i)
      visit(k, simulateScan(scene, stops[k], stops[k].first_scan + i, seed));
}

SimulatedSequence simulateSequence(const Scene& scene, const std::vector<TruthStop>& stops,
                                   std::uint64_t seed) {
  SimulatedSequence out;
  forEachScan(scene, stops, seed, [&](std::size_t k, SimulatedScan&& scan) {
    out.scans.push_back(std::move(scan));
    out.stop_of_scan.push_back(k);
  });
  return out;
}

}  // namespace lidarcal::simulation
