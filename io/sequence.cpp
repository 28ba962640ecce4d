#include "io/sequence.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"

namespace lidarcal::io {
namespace fs = std::filesystem;

namespace {

/// Takes scan i (at `v`) into the stops: the last stop's when within the tolerance of its
/// commanded pose, else a new stop.
void addToStops(std::vector<Stop>& stops, std::size_t i, const Pose2& v, const StopTolerance& tol) {
  bool same = false;
  if (!stops.empty()) {
    const Pose2& c = stops.back().commanded;
    same = std::hypot(v.x_m - c.x_m, v.y_m - c.y_m) <= tol.position_m &&
           std::abs(wrapAngle(v.yaw_rad - c.yaw_rad)) <= tol.yaw_rad;
  }
  if (same)
    stops.back().scans.grow();
  else
    stops.push_back(Stop{v, ScanRange(i, 1)});
}

}  // namespace

std::vector<Stop> groupStops(const std::vector<Pose2>& viewpoints, const StopTolerance& tol) {
  std::vector<Stop> stops;
  for (std::size_t i = 0; i < viewpoints.size(); ++i) addToStops(stops, i, viewpoints[i], tol);
  return stops;
}

std::string ScanList::path(std::size_t i) const {
  const std::size_t begin = i == 0 ? 0 : static_cast<std::size_t>(name_end_.at(i - 1));
  std::string p = dir_;
  p.append(names_, begin, static_cast<std::size_t>(name_end_.at(i)) - begin);
  return p;
}

ScanHeader ScanList::operator[](std::size_t i) const {
  ScanHeader h;
  h.path = path(i);
  h.viewpoint = viewpoints_[i];
  h.points = static_cast<std::size_t>(points_[i]);
  h.has_intensity = (flags_[i] & 1u) != 0;
  h.has_label = (flags_[i] & 2u) != 0;
  h.binary = (flags_[i] & 4u) != 0;
  return h;
}

ScanHeader ScanList::at(std::size_t i) const {
  if (i >= size()) throw std::out_of_range("ScanList::at: scan " + std::to_string(i) + " of " + std::to_string(size()));
  return (*this)[i];
}

ScanList::ScanList(std::string dir, const std::vector<std::string>& names) : dir_(std::move(dir)) {
  std::size_t chars = 0;
  for (const auto& n : names) chars += n.size();
  names_.reserve(chars);
  name_end_.reserve(names.size());
  for (const auto& n : names) {
    names_ += n;
    name_end_.push_back(names_.size());
  }
}

namespace {
std::uint8_t flagsOf(const ScanHeader& h) {
  return static_cast<std::uint8_t>((h.has_intensity ? 1u : 0u) | (h.has_label ? 2u : 0u) | (h.binary ? 4u : 0u));
}
}  // namespace

void ScanList::setHeader(std::size_t i, const ScanHeader& h) {
  if (h.path != path(i))
    throw std::invalid_argument("ScanList: header of " + h.path + " given for scan " + std::to_string(i));
  if (viewpoints_.size() != size()) {  // the headers' storage, on first use
    viewpoints_.resize(size());
    points_.resize(size());
    flags_.resize(size());
  }
  viewpoints_[i] = h.viewpoint;
  points_[i] = h.points;
  flags_[i] = flagsOf(h);
}

void ScanList::push_back(const ScanHeader& h) {
  const std::string name = h.name();
  const std::string dir = h.path.substr(0, h.path.size() - name.size());
  if (empty())
    dir_ = dir;
  else if (dir != dir_)
    throw std::invalid_argument("ScanList: " + h.path + " is not in " + dir_);
  names_ += name;
  name_end_.push_back(names_.size());
  viewpoints_.push_back(h.viewpoint);
  points_.push_back(h.points);
  flags_.push_back(flagsOf(h));
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
/// Views into the name (a sequence of 100,000 names is checked without copying them).
struct ScanNumber {
  std::string_view prefix;  ///< the stem before the digits
  std::string_view value;   ///< the digits without leading zeros ("0" for zero)
};

std::optional<ScanNumber> scanNumber(std::string_view name) {
  const std::string_view stem = name.substr(0, name.size() - 4);
  std::size_t start = stem.size();
  while (start > 0 && std::isdigit(static_cast<unsigned char>(stem[start - 1]))) --start;
  if (start == stem.size() || (start > 0 && stem[start - 1] == '.')) return std::nullopt;
  const std::string_view digits = stem.substr(start);
  const std::size_t nz = digits.find_first_not_of('0');
  return ScanNumber{stem.substr(0, start), nz == std::string_view::npos ? std::string_view("0") : digits.substr(nz)};
}

/// Numbers compare by length, then text (no overflow however long).
bool numberLess(std::string_view a, std::string_view b) {
  return a.size() != b.size() ? a.size() < b.size() : a < b;
}

/// Files are read in lexicographic order. Where names number the scans (PREFIX<digits>.pcd),
/// that order must be the numeric order and no number may appear twice: two files for one scan
/// number are two recordings mixed in one directory (or a copy); numbers without zero padding
/// (scan_2, scan_10) would be read out of order. Memory: one index per numbered file.
void checkScanNumbers(const fs::path& dir, const std::vector<std::string>& sorted) {
  std::vector<std::size_t> numbered;
  for (std::size_t i = 0; i < sorted.size(); ++i)
    if (scanNumber(sorted[i])) numbered.push_back(i);
  // One number twice: neighbours once sorted by (prefix, number); the error names the second
  // file (in reading order) of the first such pair met in reading order.
  auto key = [&](std::size_t i) {
    const ScanNumber n = *scanNumber(sorted[i]);
    return std::make_pair(n.prefix, n.value);
  };
  std::vector<std::size_t> by_number = numbered;
  std::stable_sort(by_number.begin(), by_number.end(), [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
  std::size_t clash = sorted.size(), clash_first = 0;
  for (std::size_t k = 1, run = 0; k < by_number.size(); ++k) {
    if (key(by_number[k - 1]) != key(by_number[k])) {
      run = k;  // the first file of this number (reading order: the sort is stable)
      continue;
    }
    if (by_number[k] < clash) clash = by_number[k], clash_first = by_number[run];
  }
  if (clash < sorted.size())
    throw InputError(dir.string(), sorted[clash],
                     "has the same scan number as " + sorted[clash_first] +
                         " (written with different zero padding): two recordings or a copy mixed in one sequence",
                     "keep one of the two files; a sequence directory holds one recording");
  std::unordered_map<std::string_view, std::size_t> last;  // prefix -> file last seen with it
  for (std::size_t i : numbered) {
    const ScanNumber n = *scanNumber(sorted[i]);
    auto it = last.find(n.prefix);
    if (it != last.end() && !numberLess(scanNumber(sorted[it->second])->value, n.value))
      throw InputError(dir.string(), sorted[i],
                       "sorts after " + sorted[it->second] + " but has a smaller scan number: the numbers are not "
                       "zero-padded, so the scans would be read out of order (files are read in lexicographic order)",
                       "rename the files with zero-padded numbers of one width (scan_000002.pcd, scan_000010.pcd)");
    last[n.prefix] = i;
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
  // The names move into the compact list (and the vector of strings is freed) before the headers
  // are read.
  const fs::path first = dir / files.front();
  seq.scans = ScanList(first.string().substr(0, first.string().size() - files.front().size()), files);
  const std::size_t n = files.size();
  std::vector<std::string>().swap(files);
  for (std::size_t i = 0; i < n; ++i) {
    const fs::path f = seq.scans.path(i);
    const ScanHeader h = readScanHeader(f);
    seq.scans.setHeader(i, h);
    if (seq.meta.beams && h.points != static_cast<std::size_t>(*seq.meta.beams))
      throw InputError(f.string(), "POINTS",
                       "has " + std::to_string(h.points) + " points, but sequence.json says every scan has beams = " +
                           std::to_string(*seq.meta.beams) + ": scans of another sensor (or another mode) mixed in",
                       "keep one sensor's scans per sequence directory; if this sensor's beam count varies from scan "
                       "to scan, remove `beams` from sequence.json");
    addToStops(seq.stops, i, h.viewpoint, tol);
  }
  seq.stops.shrink_to_fit();
  seq.stop_of_scan.resize(n);
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
