// SPDX-License-Identifier: BSD-3-Clause
#include "io/sequence.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/json_util.hpp"
#include "io/scan_names.hpp"

namespace lidarcal::io {
namespace fs = std::filesystem;

namespace {

/// Takes scan i (at `v`) into the stops: the last stop's when within the tolerance of its
/// commanded pose, else a new stop.
void addToStops(std::vector<Stop>& stops, std::size_t i, const Pose2& v, const StopTolerance& tol,
                bool starts_stop = false) {
  bool same = false;
  if (!stops.empty() && !starts_stop) {
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

std::vector<Stop> groupStops(const std::vector<Pose2>& viewpoints, const StopTolerance& tol,
                             const std::vector<std::size_t>& starts) {
  std::vector<Stop> stops;
  for (std::size_t i = 0; i < viewpoints.size(); ++i)
    addToStops(stops, i, viewpoints[i], tol, std::binary_search(starts.begin(), starts.end(), i));
  return stops;
}

namespace {

std::uint8_t flagsOf(const ScanHeader& h) {
  return static_cast<std::uint8_t>((h.has_intensity ? 1u : 0u) | (h.has_label ? 2u : 0u) |
                                   (h.binary ? 4u : 0u));
}

/// Bitwise, so that -0.0 and 0.0 stay apart: each scan gives back exactly what was read.
bool sameBits(double a, double b) {
  std::uint64_t x = 0, y = 0;
  std::memcpy(&x, &a, sizeof x);
  std::memcpy(&y, &b, sizeof y);
  return x == y;
}

std::size_t digitCount(std::uint64_t v) {
  std::size_t n = 1;
  while (v >= 10) v /= 10, ++n;
  return n;
}

/// The run holding scan i: the last whose start is <= i (runs are sorted by start, the first
/// starts at 0).
template <class Run>
const Run& runOf(const std::vector<Run>& runs, std::size_t i) {
  auto it = std::upper_bound(runs.begin(), runs.end(), i,
                             [](std::size_t k, const Run& r) { return k < r.start; });
  return *(it - 1);
}

}  // namespace

std::string ScanList::path(std::size_t i) const {
  if (i >= size_)
    throw std::out_of_range("ScanList::path: scan " + std::to_string(i) + " of " +
                            std::to_string(size_));
  std::string p = dir_;
  if (numbered_) {
    const NameRun& r = runOf(name_runs_, i);
    p.reserve(p.size() + prefix_.size() + std::max<std::size_t>(width_, 20) + 4);
    appendNumberedName(p, prefix_, width_, r.first + (i - r.start));
  } else {
    const std::size_t begin = i == 0 ? 0 : static_cast<std::size_t>(name_end_[i - 1]);
    p.append(names_, begin, static_cast<std::size_t>(name_end_[i]) - begin);
  }
  return p;
}

ScanHeader ScanList::operator[](std::size_t i) const {
  if (i >= headers_)
    throw std::logic_error("ScanList: the header of scan " + std::to_string(i) + " is not set");
  const HeaderRun& r = runOf(header_runs_, i);
  ScanHeader h;
  h.path = path(i);
  h.viewpoint = r.viewpoint;
  h.points = static_cast<std::size_t>(r.points);
  h.has_intensity = (r.flags & 1u) != 0;
  h.has_label = (r.flags & 2u) != 0;
  h.binary = (r.flags & 4u) != 0;
  return h;
}

ScanHeader ScanList::at(std::size_t i) const {
  if (i >= size())
    throw std::out_of_range("ScanList::at: scan " + std::to_string(i) + " of " +
                            std::to_string(size()));
  return (*this)[i];
}

ScanList::ScanList(std::string dir, const std::vector<std::string>& names) : dir_(std::move(dir)) {
  std::size_t chars = 0;
  bool one_pattern = !names.empty();
  std::optional<NumberedName> first;
  for (const auto& n : names) {
    chars += n.size();
    const std::optional<NumberedName> num = numberedName(n);
    if (!num || (first && (num->prefix != first->prefix || num->width != first->width)))
      one_pattern = false;
    if (!first) first = num;
  }
  if (one_pattern) {
    numbered_ = true;
    prefix_ = std::string(first->prefix);
    width_ = first->width;
    for (const auto& n : names) addNumber(numberedName(n)->number);
    name_runs_.shrink_to_fit();
    return;
  }
  names_.reserve(chars);
  name_end_.reserve(names.size());
  for (const auto& n : names) {
    names_ += n;
    name_end_.push_back(names_.size());
  }
  size_ = names.size();
}

ScanList ScanList::numbered(std::string dir, std::string prefix, std::size_t width,
                            const std::vector<std::uint64_t>& numbers) {
  if (width == 0) throw std::invalid_argument("ScanList::numbered: width 0");
  ScanList l;
  l.dir_ = std::move(dir);
  l.numbered_ = true;
  l.prefix_ = std::move(prefix);
  l.width_ = width;
  for (std::uint64_t v : numbers) {
    if (digitCount(v) > width)
      throw std::invalid_argument("ScanList::numbered: " + std::to_string(v) + " has more than " +
                                  std::to_string(width) + " digits");
    l.addNumber(v);
  }
  l.name_runs_.shrink_to_fit();
  return l;
}

void ScanList::appendName(const std::string& name) {
  if (size_ == 0) {  // the first name picks the form (a numbered one keeps it while they fit)
    names_.clear();
    name_end_.clear();
    name_runs_.clear();
    const std::optional<NumberedName> n = numberedName(name);
    numbered_ = n.has_value();
    if (n) prefix_ = std::string(n->prefix), width_ = n->width;
  }
  if (numbered_) {
    const std::optional<NumberedName> n = numberedName(name);
    if (n && n->prefix == prefix_ && n->width == width_) {
      addNumber(n->number);
      return;
    }
    namesToText();
  }
  names_ += name;
  name_end_.push_back(names_.size());
  ++size_;
}

void ScanList::addNumber(std::uint64_t v) {
  // v != 0: after the largest number (2^64 - 1), the count would wrap to 0
  const bool next = !name_runs_.empty() && v != 0 &&
                    name_runs_.back().first + (size_ - name_runs_.back().start) == v;
  if (!next) name_runs_.push_back(NameRun{size_, v});
  ++size_;
}

void ScanList::namesToText() {
  std::vector<NameRun> runs;
  runs.swap(name_runs_);
  numbered_ = false;
  name_end_.reserve(size_ + 1);
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const std::size_t end =
        k + 1 < runs.size() ? static_cast<std::size_t>(runs[k + 1].start) : size_;
    for (std::size_t i = static_cast<std::size_t>(runs[k].start); i < end; ++i) {
      appendNumberedName(names_, prefix_, width_, runs[k].first + (i - runs[k].start));
      name_end_.push_back(names_.size());
    }
  }
  prefix_.clear();
  width_ = 0;
}

void ScanList::appendHeader(const ScanHeader& h) {
  const std::uint8_t flags = flagsOf(h);
  const bool same = !header_runs_.empty() && [&] {
    const HeaderRun& r = header_runs_.back();
    return sameBits(r.viewpoint.x_m, h.viewpoint.x_m) &&
           sameBits(r.viewpoint.y_m, h.viewpoint.y_m) &&
           sameBits(r.viewpoint.yaw_rad, h.viewpoint.yaw_rad) && r.points == h.points &&
           r.flags == flags;
  }();
  if (!same) header_runs_.push_back(HeaderRun{headers_, h.viewpoint, h.points, flags});
  ++headers_;
}

void ScanList::setHeader(std::size_t i, const ScanHeader& h) {
  const std::string p = path(i);
  if (i != headers_)
    throw std::invalid_argument("ScanList: header of scan " + std::to_string(i) +
                                " given where that of scan " + std::to_string(headers_) +
                                " is due (headers are set in index order, each once)");
  if (h.path != p)
    throw std::invalid_argument("ScanList: header of " + h.path + " given for scan " +
                                std::to_string(i));
  appendHeader(h);
}

void ScanList::push_back(const ScanHeader& h) {
  if (headers_ != size_)
    throw std::invalid_argument("ScanList::push_back: the header of scan " +
                                std::to_string(headers_) + " is not set yet");
  const std::string name = h.name();
  const std::string dir = h.path.substr(0, h.path.size() - name.size());
  if (empty())
    dir_ = dir;
  else if (dir != dir_)
    throw std::invalid_argument("ScanList: " + h.path + " is not in " + dir_);
  appendName(name);
  appendHeader(h);
}

void ScanList::shrink_to_fit() {
  name_runs_.shrink_to_fit();
  names_.shrink_to_fit();
  name_end_.shrink_to_fit();
  header_runs_.shrink_to_fit();
}

namespace {

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
  std::stable_sort(by_number.begin(), by_number.end(),
                   [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
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
                         " (written with different zero padding): two recordings or a copy mixed "
                         "in one sequence",
                     "keep one of the two files; a sequence directory holds one recording");
  std::unordered_map<std::string_view, std::size_t> last;  // prefix -> file last seen with it
  for (std::size_t i : numbered) {
    const ScanNumber n = *scanNumber(sorted[i]);
    auto it = last.find(n.prefix);
    if (it != last.end() && !numberLess(scanNumber(sorted[it->second])->value, n.value))
      throw InputError(dir.string(), sorted[i],
                       "sorts after " + sorted[it->second] +
                           " but has a smaller scan number: the numbers are not "
                           "zero-padded, so the scans would be read out of order (files are read "
                           "in lexicographic order)",
                       "rename the files with zero-padded numbers of one width (scan_000002.pcd, "
                       "scan_000010.pcd)");
    last[n.prefix] = i;
  }
}

/// The scan file names of a directory: while every name reads PREFIX + digits of one width +
/// .pcd (what lidarcal writes), only the numbers (8 bytes a scan); else the names, sorted.
struct ScanNames {
  std::vector<std::string> files;      ///< the names, sorted (one_pattern false)
  std::vector<std::uint64_t> numbers;  ///< the numbers, sorted (one_pattern true)
  std::string prefix;                  ///< of the numbered names
  std::size_t width = 0;               ///< digits of the numbered names
  bool one_pattern = true;             ///< every name numbered alike
  std::size_t size() const { return one_pattern ? numbers.size() : files.size(); }
};

/// Throws InputError when `dir` is missing or not a directory.
void checkSequenceDirectory(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec))
    throw InputError(dir.string(), "", "sequence directory does not exist", "check the path");
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string(), "",
                     "is not a directory: a sequence is a directory of .pcd files",
                     "pass the directory that holds the scans");
}

/// File names only (a std::filesystem::path per file costs several hundred bytes: its components
/// are paths too), in order; the first name that does not fit the numbered pattern turns the
/// numbers back into names. Throws InputError for a .PCD in another case, an unreadable or empty
/// directory, and numbers that are not zero-padded.
ScanNames listScanNames(const fs::path& dir) {
  std::error_code ec;
  ScanNames names;
  std::vector<std::string>& files = names.files;
  std::vector<std::uint64_t>& numbers = names.numbers;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string name = entry.path().filename().string();
    if (name[0] == '.') continue;
    if (isPcdNameInOtherCase(name))
      throw InputError(
          entry.path().string(), "",
          "has the extension '" + name.substr(name.size() - 4) +
              "': lidarcal reads only files ending in lower-case .pcd and would skip this scan",
          "rename it to end in .pcd (mind a file of that name already present)");
    if (!isPcdName(name)) continue;
    if (names.one_pattern) {
      const std::optional<NumberedName> num = numberedName(name);
      if (num && (numbers.empty() || (num->prefix == names.prefix && num->width == names.width))) {
        if (numbers.empty()) names.prefix = std::string(num->prefix), names.width = num->width;
        numbers.push_back(num->number);
        continue;
      }
      names.one_pattern = false;
      files.reserve(numbers.size() + 1);
      for (std::uint64_t v : numbers)
        files.push_back(numberedFileName(names.prefix, names.width, v));
      std::vector<std::uint64_t>().swap(numbers);
    }
    files.push_back(std::move(name));
  }
  if (ec)
    throw InputError(dir.string(), "", "cannot list the directory (" + ec.message() + ")",
                     "check its permissions");
  if (files.empty() && numbers.empty())
    throw InputError(dir.string(), "", "holds no .pcd file: an empty sequence",
                     "point to a directory of scans (see docs/FORMAT.md), or create one with "
                     "`lidarcal simulate` or `lidarcal import`");
  if (names.one_pattern) {
    // One prefix, one width: numeric order is lexicographic order and no number can appear twice
    // (same width and value = same name), so checkScanNumbers has nothing to report here.
    std::sort(numbers.begin(), numbers.end());
  } else {
    std::sort(files.begin(), files.end());
    checkScanNumbers(dir, files);
  }
  return names;
}

/// The names moved into the compact list (the numbers or the vector of strings freed).
ScanList compactScanList(const fs::path& dir, ScanNames& names) {
  // The directory as ScanList wants it: the first path without its file name.
  auto dirOf = [&](const std::string& first_name) {
    const std::string first = (dir / first_name).string();
    return first.substr(0, first.size() - first_name.size());
  };
  if (names.one_pattern) {
    ScanList list = ScanList::numbered(
        dirOf(numberedFileName(names.prefix, names.width, names.numbers.front())), names.prefix,
        names.width, names.numbers);
    std::vector<std::uint64_t>().swap(names.numbers);
    return list;
  }
  ScanList list(dirOf(names.files.front()), names.files);
  std::vector<std::string>().swap(names.files);
  return list;
}

/// Reads every scan's header into seq.scans and groups the scans into stops (by pose within
/// `tol`, or where sequence.json's stop_starts says).
void readHeadersIntoStops(Sequence& seq, std::size_t n, const StopTolerance& tol) {
  const fs::path& dir = seq.dir;
  std::size_t next_start = 0;  // the next of seq.meta.stop_starts (sorted) to meet
  for (std::size_t i = 0; i < n; ++i) {
    const fs::path f = seq.scans.path(i);
    const ScanHeader h = readScanHeader(f);
    bool starts_stop = false;
    if (next_start < seq.meta.stop_starts.size()) {
      const std::string name = f.filename().string();
      // Scans come in name order: a listed name before this one was not among them.
      if (seq.meta.stop_starts[next_start] < name)
        throw InputError((dir / "sequence.json").string(), "stop_starts",
                         "names '" + seq.meta.stop_starts[next_start] +
                             "', which is not a scan of this directory",
                         "remove it from stop_starts or restore the scan");
      if (seq.meta.stop_starts[next_start] == name) {
        starts_stop = true;
        ++next_start;
      }
    }
    seq.scans.setHeader(i, h);
    if (seq.meta.beams && h.points != static_cast<std::size_t>(*seq.meta.beams))
      throw InputError(f.string(), "POINTS",
                       "has " + std::to_string(h.points) +
                           " points, but sequence.json says every scan has beams = " +
                           std::to_string(*seq.meta.beams) +
                           ": scans of another sensor (or another mode) mixed in",
                       "keep one sensor's scans per sequence directory; if this sensor's beam "
                       "count varies from scan "
                       "to scan, remove `beams` from sequence.json");
    addToStops(seq.stops, i, h.viewpoint, tol, starts_stop);
  }
  if (next_start < seq.meta.stop_starts.size())
    throw InputError(
        (dir / "sequence.json").string(), "stop_starts",
        "names '" + seq.meta.stop_starts[next_start] + "', which is not a scan of this directory",
        "remove it from stop_starts or restore the scan");
}

}  // namespace

Sequence openSequence(const fs::path& dir, const StopTolerance& tol) {
  checkSequenceDirectory(dir);
  Sequence seq;
  seq.dir = dir;
  ScanNames names = listScanNames(dir);
  std::error_code ec;
  const fs::path meta = dir / "sequence.json";
  if (fs::exists(meta, ec)) seq.meta = readSequenceMeta(meta);
  // The names move into the compact list before the headers are read.
  const std::size_t n = names.size();
  seq.scans = compactScanList(dir, names);
  readHeadersIntoStops(seq, n, tol);
  seq.stops.shrink_to_fit();
  seq.scans.shrink_to_fit();
  return seq;
}

std::size_t Sequence::stopOf(std::size_t i) const {
  if (i >= scans.size())
    throw std::out_of_range("Sequence::stopOf: scan " + std::to_string(i) + " of " +
                            std::to_string(scans.size()));
  // The last stop whose first scan is at or before i (stops cover the scans in order).
  const auto it =
      std::upper_bound(stops.begin(), stops.end(), i,
                       [](std::size_t scan, const Stop& s) { return scan < s.scans.front(); });
  return static_cast<std::size_t>(it - stops.begin()) - 1;
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
  if (v.has("stop_starts")) {
    for (const auto& e : v.array("stop_starts"))
      m.stop_starts.push_back(e.json().is_string() ? e.json().get<std::string>() : "");
    for (std::size_t k = 0; k < m.stop_starts.size(); ++k)
      if (m.stop_starts[k].empty() || (k > 0 && !(m.stop_starts[k - 1] < m.stop_starts[k])))
        throw InputError(file.string(), "stop_starts[" + std::to_string(k) + "]",
                         "must be scan file names, each once, in sorted order",
                         "fix sequence.json");
  }
  if (m.range_min_m && m.range_max_m && *m.range_min_m >= *m.range_max_m)
    throw InputError(file.string(), "range_min_m", "must be smaller than range_max_m",
                     "fix sequence.json");
  return m;
}

nlohmann::ordered_json sequenceMetaJson(const SequenceMeta& m) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  if (m.sensor_name) j["sensor_name"] = *m.sensor_name;
  if (m.landmark_radius_m) j["landmark_radius_m"] = *m.landmark_radius_m;
  if (m.range_min_m) j["range_min_m"] = *m.range_min_m;
  if (m.range_max_m) j["range_max_m"] = *m.range_max_m;
  if (m.beams) j["beams"] = *m.beams;
  if (!m.stop_starts.empty()) j["stop_starts"] = m.stop_starts;
  return j;
}

void writeSequenceMeta(const fs::path& file, const SequenceMeta& m) {
  writeTextAtomically(file, sequenceMetaJson(m).dump(2) + "\n");
}

}  // namespace lidarcal::io
