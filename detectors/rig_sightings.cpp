// SPDX-License-Identifier: BSD-3-Clause
#include "detectors/rig_sightings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "common/errors.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::detectors {
namespace {

/// One detection placed in the frame of the vehicle's poses.
struct Placed {
  std::size_t sensor = 0, row = 0;
  double x_m = 0.0, y_m = 0.0;
  std::vector<BeamReading> beams;
};

/// A pole being gathered: the running mean of its sightings' centres.
struct Gathered {
  double x_m = 0.0, y_m = 0.0;
  std::size_t n = 0;
  std::set<std::size_t> rows;
};

/// Retro-reflectors return far more light than anything else: dimmer points read as no return.
void dropDimPoints(io::Scan& scan, double min_intensity) {
  if (min_intensity <= 0.0 || !scan.has_intensity) return;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (auto& p : scan.cloud->points)
    if (p.intensity < min_intensity) p.x = p.y = p.z = nan;
}

/// The detection's centre in the frame of the vehicle's poses, with the sensor on the vehicle at
/// its prior mounting (common/rig.hpp: a beam at angle a points at yaw + flip a).
void place(const detectors::Detection& d, const Mounting& m, const Pose2& vehicle, Placed& out) {
  const double dir = m.beamDirection(d.bearing_rad);
  const double vx = m.x_m + d.range_m * std::cos(dir), vy = m.y_m + d.range_m * std::sin(dir);
  const double c = std::cos(vehicle.yaw_rad), s = std::sin(vehicle.yaw_rad);
  out.x_m = vehicle.x_m + c * vx - s * vy;
  out.y_m = vehicle.y_m + s * vx + c * vy;
}

std::vector<BeamReading> beamsOf(const detectors::Detection& d, const io::Scan& scan) {
  std::vector<BeamReading> beams;
  beams.reserve(d.inliers.size());
  for (const auto i : d.inliers) {
    const auto& p = scan.cloud->points[static_cast<std::size_t>(i)];
    BeamReading b;
    b.angle_rad = std::atan2(p.y, p.x);
    b.range_m = std::hypot(p.x, p.y);
    b.beam = static_cast<std::uint32_t>(i);
    if (scan.has_intensity) b.intensity = p.intensity;
    beams.push_back(b);
  }
  return beams;
}

/// Every detection of every scan of every sensor, placed.
std::vector<Placed> detectAll(const io::Rig& rig, const std::vector<RigSensor>& sensors,
                              const std::vector<Pose2>& poses, const RigDetectionSettings& s,
                              std::vector<RigSensorDetections>& counts) {
  std::vector<Placed> placed;
  for (std::size_t row = 0; row < rig.scans.size(); ++row) {
    const std::size_t k = *rig.meta.find(rig.scans[row].sensor);
    io::Scan scan = io::readScan(rig.sequences[k].scans.path(rig.scan_index[row]));
    dropDimPoints(scan, s.min_intensity);
    ++counts[k].scans;
    for (const detectors::Detection& d : detectors::detectScan(scan, s.detection).detections) {
      Placed p;
      p.sensor = k;
      p.row = row;
      place(d, sensors[k].prior, poses[row], p);
      p.beams = beamsOf(d, scan);
      placed.push_back(std::move(p));
      ++counts[k].detections;
    }
  }
  return placed;
}

/// Greedy association in reading order: each detection joins the nearest pole within reach.
std::vector<int> associate(const std::vector<Placed>& placed, double reach_m,
                           std::vector<Gathered>& poles) {
  std::vector<int> label(placed.size(), -1);
  for (std::size_t i = 0; i < placed.size(); ++i) {
    double best = reach_m;
    for (std::size_t p = 0; p < poles.size(); ++p) {
      const double d = std::hypot(placed[i].x_m - poles[p].x_m, placed[i].y_m - poles[p].y_m);
      if (d <= best) best = d, label[i] = static_cast<int>(p);
    }
    if (label[i] < 0) {
      label[i] = static_cast<int>(poles.size());
      poles.push_back(Gathered{});
    }
    Gathered& g = poles[static_cast<std::size_t>(label[i])];
    g.x_m += (placed[i].x_m - g.x_m) / static_cast<double>(g.n + 1);
    g.y_m += (placed[i].y_m - g.y_m) / static_cast<double>(g.n + 1);
    ++g.n;
    g.rows.insert(placed[i].row);
  }
  return label;
}

}  // namespace

void RigDetectionSettings::validate() const {
  detection.validate();
  if (!detection.landmark_radius_m || *detection.landmark_radius_m <= 0.0)
    throw InputError("", "--radius", "a rig needs the poles' radius",
                     "give it, e.g. --radius 0.045");
  if (!(min_intensity >= 0.0)) throw InputError("", "--min-intensity", "must be >= 0");
  if (!(associate_m > 0.0)) throw InputError("", "--associate", "must be > 0 metres");
  if (min_scans < 1) throw InputError("", "--min-scans", "must be >= 1");
}

RigCollected collectRigObservations(const io::Rig& rig, const RigDetectionSettings& s) {
  s.validate();
  RigCollected out;
  RigObservations& obs = out.observations;
  obs.vehicle_known = rig.meta.vehiclePosesKnown();
  obs.pole_radius_m = s.detection.landmark_radius_m;
  for (std::size_t k = 0; k < rig.meta.sensors.size(); ++k) {
    const io::RigSensorInfo& info = rig.meta.sensors[k];
    const io::SequenceMeta& meta = rig.sequences[k].meta;
    RigSensor sensor;
    sensor.name = info.name;
    sensor.range_min_m = meta.range_min_m.value_or(sensor.range_min_m);
    sensor.range_max_m = meta.range_max_m.value_or(sensor.range_max_m);
    sensor.prior_known = info.mounting.has_value();
    if (info.mounting) sensor.prior = *info.mounting;
    obs.sensors.push_back(sensor);
  }
  // The vehicle's pose per stop: the recorded one (first scan of the stop), or the origin when
  // none was recorded (the stops are then taken as one place).
  std::size_t stops = 0;
  for (const io::RigScan& r : rig.scans) stops = std::max(stops, r.stop + 1);
  obs.vehicle.assign(stops, Pose2{});
  std::vector<bool> set(stops, false);
  std::vector<Pose2> row_pose(rig.scans.size());
  for (std::size_t row = 0; row < rig.scans.size(); ++row) {
    const io::RigScan& r = rig.scans[row];
    if (obs.vehicle_known && !set[r.stop]) obs.vehicle[r.stop] = r.vehicle, set[r.stop] = true;
    row_pose[row] = obs.vehicle[r.stop];
  }
  out.sensors.resize(obs.sensors.size());
  const std::vector<Placed> placed = detectAll(rig, obs.sensors, row_pose, s, out.sensors);
  std::vector<Gathered> gathered;
  const std::vector<int> label = associate(placed, s.associate_m, gathered);
  // Pole ids 1.. in order of first sighting, for the poles seen in enough scans.
  std::vector<int> id(gathered.size(), 0);
  std::vector<std::set<std::size_t>> seen_by(gathered.size());
  for (std::size_t i = 0; i < placed.size(); ++i)
    seen_by[static_cast<std::size_t>(label[i])].insert(placed[i].sensor);
  for (std::size_t p = 0; p < gathered.size(); ++p)
    if (gathered[p].rows.size() >= s.min_scans) {
      id[p] = static_cast<int>(++out.poles);
      if (seen_by[p].size() > 1) ++out.shared_poles;
      for (const std::size_t k : seen_by[p]) ++out.sensors[k].poles;
    }
  for (std::size_t i = 0; i < placed.size(); ++i) {
    const int pole = id[static_cast<std::size_t>(label[i])];
    if (pole == 0) continue;
    const Placed& p = placed[i];
    obs.sightings.push_back(RigSighting{p.sensor, rig.scans[p.row].stop, p.row, pole, p.beams});
    ++out.sensors[p.sensor].sightings;
  }
  return out;
}

}  // namespace lidarcal::detectors
