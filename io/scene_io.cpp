// SPDX-License-Identifier: BSD-3-Clause
#include "io/scene_io.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace {

using ojson = nlohmann::ordered_json;

Cylinder parseCylinder(const JsonView& v) {
  v.requireObject();
  Cylinder c;
  c.x_m = v.getNumber("x_m");
  c.y_m = v.getNumber("y_m");
  c.radius_m = v.getPositive("radius_m");
  c.range_offset_m = v.getNumber("range_offset_m", 0.0);
  c.intensity = v.getNonNegative("intensity", 0.0);
  return c;
}

RangeEffects parseEffects(const JsonView& v) {
  v.requireObject();
  RangeEffects e;
  e.incidence_noise_exponent = v.getNonNegative("incidence_noise_exponent", 0.0);
  e.incidence_bias_m = v.getNumber("incidence_bias_m", 0.0);
  e.range_drift_m_per_scan = v.getNumber("range_drift_m_per_scan", 0.0);
  e.range_drift_reference_scan = v.getNonNegative("range_drift_reference_scan", 0.0);
  e.mixed_pixel_fraction = v.getNonNegative("mixed_pixel_fraction", 0.0);
  if (e.mixed_pixel_fraction > 1.0) v.fail("mixed_pixel_fraction", "must lie in [0, 1]");
  e.noise_student_dof = v.getNonNegative("noise_student_dof", 0.0);
  if (e.noise_student_dof != 0.0 && e.noise_student_dof <= 2.0)
    v.fail("noise_student_dof",
           "must be 0 (Gaussian noise) or above 2 (a Student t with finite variance)");
  e.range_resolution_m = v.getNonNegative("range_resolution_m", 0.0);
  e.dark_noise_exponent = v.getNumber("dark_noise_exponent", 0.0);
  e.dark_reference_intensity = v.getPositive("dark_reference_intensity", 1.0);
  e.ripple_amplitude_m = v.getNonNegative("ripple_amplitude_m", 0.0);
  e.ripple_wavelength_m = v.getPositive("ripple_wavelength_m", e.ripple_wavelength_m);
  e.ripple_phase_rad = v.getNumber("ripple_phase_rad", 0.0);
  return e;
}

/// The effects that are on (an empty object when none is).
ojson effectsToJson(const RangeEffects& e) {
  ojson j = ojson::object();
  if (e.incidence_noise_exponent != 0.0) j["incidence_noise_exponent"] = e.incidence_noise_exponent;
  if (e.incidence_bias_m != 0.0) j["incidence_bias_m"] = e.incidence_bias_m;
  if (e.range_drift_m_per_scan != 0.0) j["range_drift_m_per_scan"] = e.range_drift_m_per_scan;
  if (e.range_drift_reference_scan != 0.0)
    j["range_drift_reference_scan"] = e.range_drift_reference_scan;
  if (e.mixed_pixel_fraction != 0.0) j["mixed_pixel_fraction"] = e.mixed_pixel_fraction;
  if (e.noise_student_dof != 0.0) j["noise_student_dof"] = e.noise_student_dof;
  if (e.range_resolution_m != 0.0) j["range_resolution_m"] = e.range_resolution_m;
  if (e.dark_noise_exponent != 0.0) {
    j["dark_noise_exponent"] = e.dark_noise_exponent;
    j["dark_reference_intensity"] = e.dark_reference_intensity;
  }
  if (e.ripple_amplitude_m != 0.0) {
    j["ripple_amplitude_m"] = e.ripple_amplitude_m;
    j["ripple_wavelength_m"] = e.ripple_wavelength_m;
    j["ripple_phase_rad"] = e.ripple_phase_rad;
  }
  return j;
}

Pose2 parsePose(const JsonView& v) {
  Pose2 p;
  p.x_m = v.getNumber("x_m", 0.0);
  p.y_m = v.getNumber("y_m", 0.0);
  if (v.has("yaw_rad") && v.has("yaw_deg"))
    v.fail("yaw_deg", "give either yaw_deg or yaw_rad, not both");
  p.yaw_rad = v.has("yaw_rad") ? v.getNumber("yaw_rad") : deg2rad(v.getNumber("yaw_deg", 0.0));
  return p;
}

ojson poseToJson(const Pose2& p) {
  return ojson{{"x_m", p.x_m}, {"y_m", p.y_m}, {"yaw_rad", p.yaw_rad}};
}

NoiseModel parseNoise(const JsonView& v) {
  v.requireObject();
  NoiseModel n;
  const std::string kind = v.getString("kind");
  if (!parseNoiseKind(kind, n.kind))
    v.fail("kind", "unknown noise kind '" + kind +
                       "' (expected none, constant, polynomial, squared or power)");
  switch (n.kind) {
    case NoiseKind::none:
      break;
    case NoiseKind::constant:
    case NoiseKind::squared:
      n.sigma_e = v.getNonNegative("sigma_e");
      break;
    case NoiseKind::power:
      n.sigma_e = v.getNonNegative("sigma_e");
      n.exponent = v.getNumber("exponent");
      break;
    case NoiseKind::polynomial:
      n.beta = v.getNumbers("beta");
      if (n.beta.empty()) v.fail("beta", "must hold at least one coefficient");
      break;
  }
  return n;
}

ojson noiseToJson(const NoiseModel& n) {
  ojson j{{"kind", toString(n.kind)}};
  switch (n.kind) {
    case NoiseKind::none:
      break;
    case NoiseKind::constant:
    case NoiseKind::squared:
      j["sigma_e"] = n.sigma_e;
      break;
    case NoiseKind::power:
      j["sigma_e"] = n.sigma_e;
      j["exponent"] = n.exponent;
      break;
    case NoiseKind::polynomial:
      j["beta"] = n.beta;
      break;
  }
  return j;
}

/// A driving path's keys (docs/FORMAT.md, "Driving"): the route, speed and odometry noise.
void parseDriving(const JsonView& path, PathSpec& p) {
  for (const char* key : {"step_m", "stops", "scans_per_stop", "sigma_s_m", "sigma_psi_deg"})
    if (path.has(key))
      path.fail(key,
                "is a key of stop-and-go paths; a driving path takes scans, speed_m_per_scan, "
                "route and odometry");
  p.stops = path.getPositiveInt("scans");
  p.scans_per_stop = path.getPositiveInt("scans_per_pose", 1);
  if (static_cast<long long>(p.stops) * p.scans_per_stop > 10'000'000)
    path.fail("scans", "scans x scans_per_pose exceeds 10 million scans");
  DrivingSpec& d = p.driving;
  d.speed_m_per_scan = path.getPositive("speed_m_per_scan", d.speed_m_per_scan);
  if (path.has("route")) {
    d.route.clear();
    for (const auto& e : path.array("route")) {
      e.requireObject();
      RouteSegment r;
      r.length_m = e.getPositive("length_m");
      r.turn_rad = deg2rad(e.getNumber("turn_deg", 0.0));
      d.route.push_back(r);
    }
    if (d.route.empty()) path.fail("route", "needs at least one piece");
  }
  if (path.has("odometry")) {
    const JsonView o = path.child("odometry");
    o.requireObject();
    d.odometry.translation_fraction = o.getNonNegative("translation_fraction", 0.0);
    d.odometry.heading_rad_per_m = deg2rad(o.getNonNegative("heading_deg_per_m", 0.0));
    d.odometry.heading_fraction = o.getNonNegative("heading_fraction", 0.0);
  }
}

PathSpec parsePath(const JsonView& path) {
  path.requireObject();
  PathSpec p;
  const std::string kind = path.getString("kind", "stops");
  if (kind != "stops" && kind != "driving")
    path.fail("kind", "unknown path kind '" + kind + "' (expected stops or driving)");
  p.kind = kind == "driving" ? PathKind::driving : PathKind::stops;
  if (path.has("start")) p.start = parsePose(path.child("start"));
  if (p.kind == PathKind::driving) {
    parseDriving(path, p);
  } else {
    p.step_m = path.getNumber("step_m", p.step_m);
    p.stops = path.getPositiveInt("stops", p.stops);
    p.scans_per_stop = path.getPositiveInt("scans_per_stop", p.scans_per_stop);
    if (static_cast<long long>(p.stops) * p.scans_per_stop > 10'000'000)
      path.fail("stops", "stops x scans_per_stop exceeds 10 million scans");
    p.sigma_s_m = path.getNonNegative("sigma_s_m", 0.0);
    p.sigma_psi_rad = deg2rad(path.getNonNegative("sigma_psi_deg", 0.0));
  }
  p.step_error_fraction = path.getNumber("step_error_fraction", 0.0);
  if (!(p.step_error_fraction > -1.0)) path.fail("step_error_fraction", "must be above -1");
  return p;
}

/// The path as JSON: a stop-and-go path with exactly the keys it always had (scenes keep their
/// bytes), a driving path with its own keys.
ojson pathToJson(const PathSpec& p) {
  const ojson start{
      {"x_m", p.start.x_m}, {"y_m", p.start.y_m}, {"yaw_deg", rad2deg(p.start.yaw_rad)}};
  ojson path;
  if (p.kind == PathKind::driving) {
    ojson route = ojson::array();
    for (const auto& r : p.driving.route)
      route.push_back(ojson{{"length_m", r.length_m}, {"turn_deg", rad2deg(r.turn_rad)}});
    const OdometryNoise& o = p.driving.odometry;
    path = ojson{{"kind", "driving"},
                 {"start", start},
                 {"scans", p.stops},
                 {"scans_per_pose", p.scans_per_stop},
                 {"speed_m_per_scan", p.driving.speed_m_per_scan},
                 {"route", route},
                 {"odometry", ojson{{"translation_fraction", o.translation_fraction},
                                    {"heading_deg_per_m", rad2deg(o.heading_rad_per_m)},
                                    {"heading_fraction", o.heading_fraction}}}};
  } else {
    path = ojson{{"start", start},           {"step_m", p.step_m},
                 {"stops", p.stops},         {"scans_per_stop", p.scans_per_stop},
                 {"sigma_s_m", p.sigma_s_m}, {"sigma_psi_deg", rad2deg(p.sigma_psi_rad)}};
  }
  if (p.step_error_fraction != 0.0) path["step_error_fraction"] = p.step_error_fraction;
  return path;
}

Scene parseScene(const JsonView& root) {
  root.requireObject();
  Scene s;
  s.name = root.getString("name", s.name);

  const JsonView sensor = root.child("sensor");
  SensorSpec& spec = s.sensor;
  spec.name = sensor.getString("name", spec.name);
  spec.beams = sensor.getPositiveInt("beams", spec.beams);
  if (spec.beams > 1'000'000)
    sensor.fail("beams", "more than a million beams per scan is not a 2D lidar");
  spec.angle_min_rad = deg2rad(sensor.getNumber("angle_min_deg", 0.0));
  spec.angle_increment_rad = deg2rad(sensor.getPositive("angle_increment_deg", 360.0 / spec.beams));
  spec.range.range_min_m = sensor.getNonNegative("range_min_m");
  spec.range.range_max_m = sensor.getPositive("range_max_m");
  if (spec.range.range_min_m >= spec.range.range_max_m)
    sensor.fail("range_min_m", "must be smaller than range_max_m");
  spec.range.bias.alpha =
      sensor.has("bias_alpha") ? sensor.getNumbers("bias_alpha") : std::vector<double>{0.0, 1.0};
  if (spec.range.bias.alpha.empty() || spec.range.bias.alpha.size() > 10)
    sensor.fail("bias_alpha", "must hold 1 to 10 coefficients alpha_0..alpha_n");
  if (sensor.has("noise"))
    spec.range.noise = parseNoise(sensor.child("noise"));
  else
    spec.range.noise.kind = NoiseKind::none;
  spec.bearing_noise_rad = deg2rad(sensor.getNonNegative("bearing_noise_deg", 0.0));
  spec.mount_yaw_rad = deg2rad(sensor.getNumber("mount_yaw_deg", 0.0));
  if (sensor.has("effects")) spec.effects = parseEffects(sensor.child("effects"));

  s.path = parsePath(root.child("path"));

  if (root.has("landmarks"))
    for (const auto& e : root.array("landmarks")) s.landmarks.push_back(parseCylinder(e));
  if (root.has("clutter"))
    for (const auto& e : root.array("clutter")) s.clutter.push_back(parseCylinder(e));
  if (root.has("walls"))
    for (const auto& e : root.array("walls")) {
      e.requireObject();
      Segment w{e.getNumber("x0_m"),
                e.getNumber("y0_m"),
                e.getNumber("x1_m"),
                e.getNumber("y1_m"),
                e.getNumber("range_offset_m", 0.0),
                e.getNonNegative("intensity", 0.0)};
      if (std::hypot(w.x1_m - w.x0_m, w.y1_m - w.y0_m) <= 0.0) e.fail("", "wall has zero length");
      s.walls.push_back(w);
    }
  s.publish_landmark_radius = root.getBool("publish_landmark_radius", true);
  return s;
}

}  // namespace

Scene readScene(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  return parseScene(JsonView(file.string(), j));
}

nlohmann::ordered_json sceneToJson(const Scene& s) {
  ojson sensor{{"name", s.sensor.name},
               {"beams", s.sensor.beams},
               {"angle_min_deg", rad2deg(s.sensor.angle_min_rad)},
               {"angle_increment_deg", rad2deg(s.sensor.angle_increment_rad)},
               {"range_min_m", s.sensor.range.range_min_m},
               {"range_max_m", s.sensor.range.range_max_m},
               {"bias_alpha", s.sensor.range.bias.alpha},
               {"noise", noiseToJson(s.sensor.range.noise)},
               {"bearing_noise_deg", rad2deg(s.sensor.bearing_noise_rad)},
               {"mount_yaw_deg", rad2deg(s.sensor.mount_yaw_rad)}};
  // Keys of the effects only when set, so that scenes without effects keep their bytes.
  if (s.sensor.effects.any()) sensor["effects"] = effectsToJson(s.sensor.effects);
  const ojson path = pathToJson(s.path);
  auto cylinders = [](const std::vector<Cylinder>& cs) {
    ojson a = ojson::array();
    for (const auto& c : cs) {
      a.push_back(ojson{{"x_m", c.x_m}, {"y_m", c.y_m}, {"radius_m", c.radius_m}});
      if (c.range_offset_m != 0.0) a.back()["range_offset_m"] = c.range_offset_m;
      if (c.intensity != 0.0) a.back()["intensity"] = c.intensity;
    }
    return a;
  };
  ojson walls = ojson::array();
  for (const auto& w : s.walls) {
    walls.push_back(ojson{{"x0_m", w.x0_m}, {"y0_m", w.y0_m}, {"x1_m", w.x1_m}, {"y1_m", w.y1_m}});
    if (w.range_offset_m != 0.0) walls.back()["range_offset_m"] = w.range_offset_m;
    if (w.intensity != 0.0) walls.back()["intensity"] = w.intensity;
  }
  return ojson{{"name", s.name},
               {"sensor", sensor},
               {"path", path},
               {"landmarks", cylinders(s.landmarks)},
               {"clutter", cylinders(s.clutter)},
               {"walls", walls},
               {"publish_landmark_radius", s.publish_landmark_radius}};
}

void writeTruth(const std::filesystem::path& file, const Truth& t) {
  ojson landmarks = ojson::array();
  for (std::size_t i = 0; i < t.scene.landmarks.size(); ++i) {
    const auto& c = t.scene.landmarks[i];
    landmarks.push_back(
        ojson{{"id", i + 1}, {"x_m", c.x_m}, {"y_m", c.y_m}, {"radius_m", c.radius_m}});
  }
  ojson stops = ojson::array();
  for (std::size_t k = 0; k < t.stops.size(); ++k) {
    const auto& s = t.stops[k];
    stops.push_back(ojson{{"stop", k},
                          {"commanded", poseToJson(s.commanded)},
                          {"actual", poseToJson(s.actual)},
                          {"first_scan", s.first_scan},
                          {"scans", s.scans}});
  }
  const auto& r = t.scene.sensor.range;
  ojson j{{"format", "lidarcal-truth/1"},
          {"seed", t.seed},
          {"landmarks", landmarks},
          {"model", ojson{{"bias_alpha", r.bias.alpha},
                          {"noise", noiseToJson(r.noise)},
                          {"range_min_m", r.range_min_m},
                          {"range_max_m", r.range_max_m}}},
          {"stops", stops},
          {"true_ranges_file", t.true_ranges_file},
          {"scene", sceneToJson(t.scene)}};
  writeTextAtomically(file, j.dump(2) + "\n");
}

Truth readTruth(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  const JsonView root(file.string(), j);
  root.requireObject();
  if (root.getString("format", "") != "lidarcal-truth/1")
    root.fail("format", "not a lidarcal truth file (expected \"lidarcal-truth/1\")");
  Truth t;
  const auto& seed = j.at("seed");
  if (!seed.is_number_unsigned()) root.fail("seed", "must be a non-negative integer");
  t.seed = seed.get<std::uint64_t>();
  t.scene = parseScene(root.child("scene"));
  t.true_ranges_file = root.getString("true_ranges_file", t.true_ranges_file);
  for (const auto& e : root.array("stops")) {
    e.requireObject();
    TruthStop s;
    s.commanded = parsePose(e.child("commanded"));
    s.actual = parsePose(e.child("actual"));
    s.first_scan = static_cast<std::size_t>(e.getNonNegative("first_scan"));
    s.scans = static_cast<std::size_t>(e.getNonNegative("scans"));
    t.stops.push_back(s);
  }
  return t;
}

}  // namespace lidarcal::io
