// SPDX-License-Identifier: BSD-3-Clause
#include "io/reference_io.hpp"

#include <cmath>
#include <cstdio>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "common/plural.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace {

constexpr const char* kFormat = "lidarcal-reference/1";

/// Fails on a member of `v` that is not in `known` (a misspelt key must not pass silently).
void rejectUnknownKeys(const JsonView& v, std::initializer_list<const char*> known) {
  for (const auto& [key, value] : v.json().items()) {
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) v.fail(key, "is not a field of this entry (misspelt?)");
  }
}

std::size_t stopIndex(const JsonView& e) {
  const int stop = e.getInt("stop");
  if (stop < 0) e.fail("stop", "must be a stop index (0, 1, ...)");
  return static_cast<std::size_t>(stop);
}

ReferenceDistance readDistance(const JsonView& e) {
  e.requireObject();
  rejectUnknownKeys(e, {"stop", "target", "distance_m", "bearing_rad", "sigma_m"});
  ReferenceDistance d;
  d.stop = stopIndex(e);
  const std::string target = e.getString("target", "landmark");
  if (target == "landmark")
    d.target = ReferenceTarget::landmark;
  else if (target == "wall")
    d.target = ReferenceTarget::wall;
  else
    e.fail("target", "must be \"landmark\" or \"wall\", not \"" + target + "\"");
  d.distance_m = e.getPositive("distance_m");
  if (e.has("bearing_rad")) {
    const double b = e.getNumber("bearing_rad");
    if (!(std::abs(b) <= 2.0 * 3.14159265358979323846))
      e.fail("bearing_rad", "must be an angle in radians (-2 pi..2 pi)");
    d.bearing_rad = b;
  }
  d.sigma_m = e.getNonNegative("sigma_m", d.sigma_m);  // 0: the distance is taken as exact
  return d;
}

/// A wall's normal direction in degrees (any turn, kept in radians).
double readBearingDeg(const JsonView& e, const std::string& key) {
  const double deg = e.getNumber(key);
  if (!(std::abs(deg) <= 360.0)) e.fail(key, "must be an angle in degrees (-360..360)");
  return deg2rad(deg);
}

ReferenceSpan readSpan(const JsonView& e) {
  e.requireObject();
  rejectUnknownKeys(e, {"stop", "bearing_a_deg", "bearing_b_deg", "distance_m", "sigma_m"});
  ReferenceSpan s;
  s.stop = stopIndex(e);
  s.bearing_a_rad = readBearingDeg(e, "bearing_a_deg");
  s.bearing_b_rad = readBearingDeg(e, "bearing_b_deg");
  // The sensor stands between the two walls: their normals point away from each other.
  const double apart = rad2deg(std::abs(wrapAngle(s.bearing_a_rad - s.bearing_b_rad)));
  if (apart < 90.0) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "is %.0f degrees from bearing_a_deg: the two walls of a span lie on opposite "
                  "sides of the sensor, "
                  "their normal directions about 180 degrees apart",
                  apart);
    e.fail("bearing_b_deg", text);
  }
  s.distance_m = e.getPositive("distance_m");
  s.sigma_m = e.getPositive("sigma_m", s.sigma_m);
  return s;
}

}  // namespace

Reference readReference(const std::filesystem::path& file) {
  const nlohmann::json j = readJsonFile(file);
  const JsonView root(file.string(), j);
  root.requireObject();
  rejectUnknownKeys(root, {"format", "distances", "landmarks", "stops", "spans"});
  if (root.getString("format", "") != kFormat)
    root.fail("format",
              std::string("not a lidarcal reference file (expected \"") + kFormat + "\")");
  Reference ref;
  if (root.has("distances"))
    for (const auto& e : root.array("distances")) ref.distances.push_back(readDistance(e));
  if (root.has("landmarks"))
    for (const auto& e : root.array("landmarks")) {
      e.requireObject();
      rejectUnknownKeys(e, {"x_m", "y_m", "radius_m"});
      ReferenceLandmark l;
      l.x_m = e.getNumber("x_m");
      l.y_m = e.getNumber("y_m");
      if (e.has("radius_m")) l.radius_m = e.getPositive("radius_m");
      ref.landmarks.push_back(l);
    }
  if (root.has("stops"))
    for (const auto& e : root.array("stops")) {
      e.requireObject();
      rejectUnknownKeys(e, {"stop", "x_m", "y_m", "yaw_rad"});
      ReferenceStop s;
      s.stop = stopIndex(e);
      s.pose = Pose2{e.getNumber("x_m"), e.getNumber("y_m"), e.getNumber("yaw_rad")};
      ref.stops.push_back(s);
    }
  if (root.has("spans"))
    for (const auto& e : root.array("spans")) ref.spans.push_back(readSpan(e));
  if (ref.empty())
    root.fail("",
              "holds no measurement: give at least one of distances, spans, landmarks or stops");
  // Two surveyed landmarks closer than their radii are one pole written twice.
  for (std::size_t a = 0; a < ref.landmarks.size(); ++a)
    for (std::size_t b = a + 1; b < ref.landmarks.size(); ++b)
      if (std::hypot(ref.landmarks[a].x_m - ref.landmarks[b].x_m,
                     ref.landmarks[a].y_m - ref.landmarks[b].y_m) < 0.01)
        throw InputError(
            file.string(), "landmarks[" + std::to_string(b) + "]",
            "is within 1 cm of landmarks[" + std::to_string(a) + "]: one pole listed twice",
            "remove one of the two entries");
  return ref;
}

void checkReference(const Reference& ref, std::size_t stops, const std::filesystem::path& file) {
  auto inRange = [&](std::size_t stop, const std::string& entry) {
    if (stop >= stops)
      throw InputError(file.string(), entry + ".stop",
                       "is stop " + std::to_string(stop) + " but the sequence has " +
                           plural(stops, "stop") + ", numbered from 0",
                       "number the stops as `lidarcal info` lists them (import --stop-per-input "
                       "makes one per recording)");
  };
  for (std::size_t k = 0; k < ref.distances.size(); ++k)
    inRange(ref.distances[k].stop, "distances[" + std::to_string(k) + "]");
  for (std::size_t k = 0; k < ref.spans.size(); ++k)
    inRange(ref.spans[k].stop, "spans[" + std::to_string(k) + "]");
  std::set<std::size_t> seen;
  for (std::size_t k = 0; k < ref.stops.size(); ++k) {
    const std::string entry = "stops[" + std::to_string(k) + "]";
    inRange(ref.stops[k].stop, entry);
    if (!seen.insert(ref.stops[k].stop).second)
      throw InputError(file.string(), entry + ".stop",
                       "measures stop " + std::to_string(ref.stops[k].stop) + " a second time",
                       "keep one pose per stop");
  }
}

void writeReference(const std::filesystem::path& file, const Reference& ref) {
  nlohmann::ordered_json j{{"format", kFormat}};
  if (!ref.distances.empty()) {
    auto a = nlohmann::ordered_json::array();
    for (const auto& d : ref.distances) {
      nlohmann::ordered_json e{{"stop", d.stop},
                               {"target", d.target == ReferenceTarget::wall ? "wall" : "landmark"},
                               {"distance_m", d.distance_m}};
      if (d.bearing_rad) e["bearing_rad"] = *d.bearing_rad;
      e["sigma_m"] = d.sigma_m;
      a.push_back(e);
    }
    j["distances"] = a;
  }
  if (!ref.landmarks.empty()) {
    auto a = nlohmann::ordered_json::array();
    for (const auto& l : ref.landmarks) {
      nlohmann::ordered_json e{{"x_m", l.x_m}, {"y_m", l.y_m}};
      if (l.radius_m) e["radius_m"] = *l.radius_m;
      a.push_back(e);
    }
    j["landmarks"] = a;
  }
  if (!ref.spans.empty()) {
    auto a = nlohmann::ordered_json::array();
    for (const auto& s : ref.spans)
      a.push_back({{"stop", s.stop},
                   {"bearing_a_deg", rad2deg(s.bearing_a_rad)},
                   {"bearing_b_deg", rad2deg(s.bearing_b_rad)},
                   {"distance_m", s.distance_m},
                   {"sigma_m", s.sigma_m}});
    j["spans"] = a;
  }
  if (!ref.stops.empty()) {
    auto a = nlohmann::ordered_json::array();
    for (const auto& s : ref.stops)
      a.push_back({{"stop", s.stop},
                   {"x_m", s.pose.x_m},
                   {"y_m", s.pose.y_m},
                   {"yaw_rad", s.pose.yaw_rad}});
    j["stops"] = a;
  }
  writeTextAtomically(file, j.dump(2) + "\n");
}

}  // namespace lidarcal::io
