#include "simulation/simulator.hpp"

#include <cmath>
#include <limits>

#include "common/rng.hpp"
#include "io/sequence.hpp"
#include "simulation/raycast.hpp"

namespace lidarcal::simulation {

double rangeReading(const RangeModel& model, double d_m, double unit_normal) {
  return model.bias(d_m) + model.noise.stddev(d_m, model.bias) * unit_normal;
}

std::vector<TruthStop> planStops(const Scene& scene, std::uint64_t seed) {
  auto rng = makeRng(seed, 0);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<TruthStop> stops;
  stops.reserve(static_cast<std::size_t>(scene.path.stops));
  for (int k = 0; k < scene.path.stops; ++k) {
    TruthStop s;
    s.commanded = commandedPose(scene.path, k);
    s.actual = s.commanded;
    // Eq. 8: the true position scatters around the commanded one, independently per stop.
    const double ex = normal(rng), ey = normal(rng), epsi = normal(rng);
    s.actual.x_m += scene.path.sigma_s_m * ex;
    s.actual.y_m += scene.path.sigma_s_m * ey;
    s.actual.yaw_rad = wrapAngle(s.actual.yaw_rad + scene.path.sigma_psi_rad * epsi);
    s.first_scan = static_cast<std::size_t>(k) * static_cast<std::size_t>(scene.path.scans_per_stop);
    s.scans = static_cast<std::size_t>(scene.path.scans_per_stop);
    stops.push_back(s);
  }
  return stops;
}

SimulatedScan simulateScan(const Scene& scene, const TruthStop& stop, std::size_t scan_index, std::uint64_t seed) {
  const SensorSpec& sensor = scene.sensor;
  const RangeModel& model = sensor.range;
  const auto n = static_cast<std::size_t>(sensor.beams);
  auto rng = makeRng(seed, scan_index + 1);
  std::normal_distribution<double> normal(0.0, 1.0);

  SimulatedScan out;
  out.scan.name = io::scanFileName(scan_index);
  out.scan.viewpoint = stop.commanded;
  out.scan.cloud.reset(new pcl::PointCloud<pcl::PointXYZI>);
  out.scan.cloud->resize(n);
  out.scan.cloud->width = static_cast<std::uint32_t>(n);
  out.scan.cloud->height = 1;
  out.scan.cloud->is_dense = true;
  out.truth.resize(n);

  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t b = 0; b < n; ++b) {
    // Draw both numbers for every beam, hit or not, so streams stay aligned across scenes.
    const double jitter = normal(rng), e = normal(rng);
    const double beam_rad = sensor.angle_min_rad + static_cast<double>(b) * sensor.angle_increment_rad;
    const double world_rad = stop.actual.yaw_rad + sensor.mount_yaw_rad + beam_rad + sensor.bearing_noise_rad * jitter;
    const Ray ray{stop.actual.x_m, stop.actual.y_m, std::cos(world_rad), std::sin(world_rad)};
    const RayHit hit = castRay(scene, ray);

    io::TrueRange& t = out.truth[b];
    t.scan = static_cast<std::uint32_t>(scan_index);
    t.beam = static_cast<std::uint32_t>(b);
    t.range_m = hit.kind == io::TargetKind::none ? std::numeric_limits<double>::quiet_NaN() : hit.range_m;
    t.target = hit.kind;
    t.target_id = hit.id;
    t.incidence_rad = hit.incidence_rad;

    auto& pt = (*out.scan.cloud)[b];
    pt.intensity = 0.0f;
    double reading = std::numeric_limits<double>::quiet_NaN();
    if (hit.kind != io::TargetKind::none) reading = rangeReading(model, hit.range_m, e);
    // The sensor reports only readings inside its window; anything else is a beam without return.
    if (!(reading >= model.range_min_m && reading <= model.range_max_m)) {
      pt.x = pt.y = pt.z = kNaN;
      out.scan.cloud->is_dense = false;
      continue;
    }
    pt.x = static_cast<float>(reading * std::cos(beam_rad));
    pt.y = static_cast<float>(reading * std::sin(beam_rad));
    pt.z = 0.0f;
  }
  return out;
}

}  // namespace lidarcal::simulation
