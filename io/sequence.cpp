#include "io/sequence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace fs = std::filesystem;

std::vector<Stop> groupStops(const std::vector<Pose2>& viewpoints, const StopTolerance& tol) {
  std::vector<Stop> stops;
  for (std::size_t i = 0; i < viewpoints.size(); ++i) {
    const Pose2& v = viewpoints[i];
    bool same = false;
    if (!stops.empty()) {
      const Pose2& c = stops.back().commanded;
      same = std::hypot(v.x_m - c.x_m, v.y_m - c.y_m) <= tol.position_m &&
             std::abs(wrapAngle(v.yaw_rad - c.yaw_rad)) <= tol.yaw_rad;
    }
    if (!same) stops.push_back(Stop{v, {}});
    stops.back().scans.push_back(i);
  }
  return stops;
}

std::string scanFileName(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "scan_%06zu.pcd", index);
  return name;
}

Sequence openSequence(const fs::path& dir, const StopTolerance& tol) {
  std::error_code ec;
  if (!fs::exists(dir, ec))
    throw InputError(dir.string(), "", "sequence directory does not exist", "check the path");
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string(), "", "is not a directory: a sequence is a directory of .pcd files",
                     "pass the directory that holds the scans");
  Sequence seq;
  seq.dir = dir;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    const fs::path& p = entry.path();
    if (p.extension() == ".pcd" && p.filename().string()[0] != '.') files.push_back(p);
  }
  if (ec) throw InputError(dir.string(), "", "cannot list the directory (" + ec.message() + ")", "check its permissions");
  if (files.empty())
    throw InputError(dir.string(), "", "holds no .pcd file: an empty sequence",
                     "point to a directory of scans (see docs/FORMAT.md), or create one with `lidarcal simulate` or `lidarcal import`");
  std::sort(files.begin(), files.end(),
            [](const fs::path& a, const fs::path& b) { return a.filename().string() < b.filename().string(); });
  seq.scans.reserve(files.size());
  std::vector<Pose2> viewpoints;
  viewpoints.reserve(files.size());
  for (const auto& f : files) {
    seq.scans.push_back(readScanHeader(f));
    viewpoints.push_back(seq.scans.back().viewpoint);
  }
  seq.stops = groupStops(viewpoints, tol);
  seq.stop_of_scan.resize(files.size());
  for (std::size_t s = 0; s < seq.stops.size(); ++s)
    for (std::size_t i : seq.stops[s].scans) seq.stop_of_scan[i] = s;
  const fs::path meta = dir / "sequence.json";
  if (fs::exists(meta, ec)) seq.meta = readSequenceMeta(meta);
  return seq;
}

SequenceMeta readSequenceMeta(const fs::path& file) {
  const nlohmann::json j = readJsonFile(file);
  JsonView v(file.string(), j);
  v.requireObject();
  SequenceMeta m;
  if (v.has("sensor_name")) m.sensor_name = v.getString("sensor_name");
  if (v.has("landmark_radius_m")) m.landmark_radius_m = v.getPositive("landmark_radius_m");
  if (v.has("range_min_m")) m.range_min_m = v.getNonNegative("range_min_m");
  if (v.has("range_max_m")) m.range_max_m = v.getPositive("range_max_m");
  if (v.has("beams")) m.beams = v.getPositiveInt("beams");
  if (m.range_min_m && m.range_max_m && *m.range_min_m >= *m.range_max_m)
    throw InputError(file.string(), "range_min_m", "must be smaller than range_max_m", "fix sequence.json");
  return m;
}

void writeSequenceMeta(const fs::path& file, const SequenceMeta& m) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  if (m.sensor_name) j["sensor_name"] = *m.sensor_name;
  if (m.landmark_radius_m) j["landmark_radius_m"] = *m.landmark_radius_m;
  if (m.range_min_m) j["range_min_m"] = *m.range_min_m;
  if (m.range_max_m) j["range_max_m"] = *m.range_max_m;
  if (m.beams) j["beams"] = *m.beams;
  writeTextAtomically(file, j.dump(2) + "\n");
}

}  // namespace lidarcal::io
