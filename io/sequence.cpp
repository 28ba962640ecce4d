#include "io/sequence.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <unordered_map>

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

namespace {

bool isPcdName(const std::string& name) {
  return name.size() > 4 && name.compare(name.size() - 4, 4, ".pcd") == 0;
}

/// `.PCD`, `.Pcd`, ...: a scan the user meant, with an extension lidarcal would skip.
bool isPcdNameInOtherCase(const std::string& name) {
  if (name.size() <= 4 || isPcdName(name)) return false;
  std::string ext = name.substr(name.size() - 4);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".pcd";
}

/// A scan name `PREFIX<digits>.pcd`: the digits are the scan number. No number when the stem
/// does not end in a digit or the digits follow a '.' (a decimal fraction, e.g. a time stamp).
struct ScanNumber {
  std::string prefix;   ///< the stem before the digits
  std::string digits;   ///< the digits as written
  std::string value;    ///< the digits without leading zeros ("0" for zero)
};

std::optional<ScanNumber> scanNumber(const std::string& name) {
  const std::string stem = name.substr(0, name.size() - 4);
  std::size_t start = stem.size();
  while (start > 0 && std::isdigit(static_cast<unsigned char>(stem[start - 1]))) --start;
  if (start == stem.size() || (start > 0 && stem[start - 1] == '.')) return std::nullopt;
  ScanNumber n{stem.substr(0, start), stem.substr(start), {}};
  const std::size_t nz = n.digits.find_first_not_of('0');
  n.value = nz == std::string::npos ? "0" : n.digits.substr(nz);
  return n;
}

/// Numbers compare by length, then text (no overflow however long).
bool numberLess(const std::string& a, const std::string& b) {
  return a.size() != b.size() ? a.size() < b.size() : a < b;
}

/// Files are read in lexicographic order. Where names number the scans (PREFIX<digits>.pcd),
/// that order must be the numeric order and no number may appear twice: two files for one scan
/// number are two recordings mixed in one directory (or a copy); numbers without zero padding
/// (scan_2, scan_10) would be read out of order.
void checkScanNumbers(const fs::path& dir, const std::vector<std::string>& sorted) {
  std::vector<std::pair<std::string, ScanNumber>> numbered;  // (file name, number)
  for (const auto& name : sorted)
    if (auto n = scanNumber(name)) numbered.emplace_back(name, std::move(*n));
  std::unordered_map<std::string, const std::string*> first;  // prefix + '/' + value -> file name
  for (const auto& [name, n] : numbered) {
    const auto [it, fresh] = first.emplace(n.prefix + "/" + n.value, &name);
    if (!fresh)
      throw InputError(dir.string(), name,
                       "has the same scan number as " + *it->second +
                           " (written with different zero padding): two recordings or a copy mixed in one sequence",
                       "keep one of the two files; a sequence directory holds one recording");
  }
  std::unordered_map<std::string, std::pair<std::string, std::string>> last;  // prefix -> (value, file name)
  for (const auto& [name, n] : numbered) {
    auto it = last.find(n.prefix);
    if (it != last.end() && !numberLess(it->second.first, n.value))
      throw InputError(dir.string(), name,
                       "sorts after " + it->second.second + " but has a smaller scan number: the numbers are not "
                       "zero-padded, so the scans would be read out of order (files are read in lexicographic order)",
                       "rename the files with zero-padded numbers of one width (scan_000002.pcd, scan_000010.pcd)");
    last[n.prefix] = {n.value, name};
  }
}

}  // namespace

Sequence openSequence(const fs::path& dir, const StopTolerance& tol) {
  std::error_code ec;
  if (!fs::exists(dir, ec))
    throw InputError(dir.string(), "", "sequence directory does not exist", "check the path");
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string(), "", "is not a directory: a sequence is a directory of .pcd files",
                     "pass the directory that holds the scans");
  Sequence seq;
  seq.dir = dir;
  // File names only (a std::filesystem::path per file costs several hundred bytes: its
  // components are paths too), then one path per scan header.
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string name = entry.path().filename().string();
    if (name[0] == '.') continue;
    if (isPcdNameInOtherCase(name))
      throw InputError(entry.path().string(), "", "has the extension '" + name.substr(name.size() - 4) +
                                                      "': lidarcal reads only files ending in lower-case .pcd and would skip this scan",
                       "rename it to end in .pcd (mind a file of that name already present)");
    if (isPcdName(name)) files.push_back(std::move(name));
  }
  if (ec) throw InputError(dir.string(), "", "cannot list the directory (" + ec.message() + ")", "check its permissions");
  if (files.empty())
    throw InputError(dir.string(), "", "holds no .pcd file: an empty sequence",
                     "point to a directory of scans (see docs/FORMAT.md), or create one with `lidarcal simulate` or `lidarcal import`");
  std::sort(files.begin(), files.end());
  checkScanNumbers(dir, files);
  const fs::path meta = dir / "sequence.json";
  if (fs::exists(meta, ec)) seq.meta = readSequenceMeta(meta);
  seq.scans.reserve(files.size());
  std::vector<Pose2> viewpoints;
  viewpoints.reserve(files.size());
  for (const auto& name : files) {
    const fs::path f = dir / name;
    seq.scans.push_back(readScanHeader(f));
    const ScanHeader& h = seq.scans.back();
    if (seq.meta.beams && h.points != static_cast<std::size_t>(*seq.meta.beams))
      throw InputError(f.string(), "POINTS",
                       "has " + std::to_string(h.points) + " points, but sequence.json says every scan has beams = " +
                           std::to_string(*seq.meta.beams) + ": scans of another sensor (or another mode) mixed in",
                       "keep one sensor's scans per sequence directory; if this sensor's beam count varies from scan "
                       "to scan, remove `beams` from sequence.json");
    viewpoints.push_back(h.viewpoint);
  }
  seq.stops = groupStops(viewpoints, tol);
  seq.stop_of_scan.resize(files.size());
  for (std::size_t s = 0; s < seq.stops.size(); ++s)
    for (std::size_t i : seq.stops[s].scans) seq.stop_of_scan[i] = s;
  return seq;
}

std::pair<std::size_t, std::size_t> pointCountRange(const Sequence& seq) {
  std::pair<std::size_t, std::size_t> r{0, 0};
  for (std::size_t i = 0; i < seq.scans.size(); ++i) {
    const std::size_t n = seq.scans[i].points;
    r.first = i == 0 ? n : std::min(r.first, n);
    r.second = std::max(r.second, n);
  }
  return r;
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
