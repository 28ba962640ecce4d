// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A scan sequence: a directory of .pcd files in lexicographic order, grouped into stops by
// their VIEWPOINT, with optional metadata in sequence.json (docs/FORMAT.md).
// Opening a sequence reads headers only; scans are loaded one at a time with readScan().

#include <cstdint>
#include <filesystem>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "common/pose2.hpp"
#include "io/pcd_scan.hpp"

namespace lidarcal::io {

/// Optional metadata of a sequence (sequence.json). Ground truth never lives here.
struct SequenceMeta {
  std::optional<std::string> sensor_name;   ///< free text, e.g. "RPLIDAR A2"
  std::optional<double> landmark_radius_m;  ///< common radius of the landmarks, when known
  std::optional<double> range_min_m;        ///< smallest range the sensor reports
  std::optional<double> range_max_m;        ///< largest range the sensor reports
  std::optional<int> beams;                 ///< beams per scan
  /// Scan files that begin a new stop even where the VIEWPOINT does not change (recordings
  /// taken apart at one pose, e.g. `lidarcal import --stop-per-input`), sorted; empty: stops
  /// by VIEWPOINT alone.
  std::vector<std::string> stop_starts;
};

/// Scan indices first, first + 1, ..., first + size - 1 (a stop's scans are consecutive).
class ScanRange {
 public:
  class iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = std::size_t;
    using difference_type = std::ptrdiff_t;
    using pointer = const std::size_t*;
    using reference = std::size_t;
    iterator() = default;
    explicit iterator(std::size_t i) : i_(i) {}
    std::size_t operator*() const { return i_; }
    iterator& operator++() {
      ++i_;
      return *this;
    }
    iterator operator++(int) {
      iterator t = *this;
      ++i_;
      return t;
    }
    bool operator==(const iterator& o) const { return i_ == o.i_; }
    bool operator!=(const iterator& o) const { return i_ != o.i_; }

   private:
    std::size_t i_ = 0;
  };
  ScanRange() = default;
  ScanRange(std::size_t first, std::size_t size) : first_(first), size_(size) {}
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t front() const { return first_; }
  std::size_t back() const { return first_ + size_ - 1; }
  std::size_t operator[](std::size_t k) const { return first_ + k; }
  iterator begin() const { return iterator(first_); }
  iterator end() const { return iterator(first_ + size_); }
  void grow() { ++size_; }  ///< takes in the next scan
 private:
  std::size_t first_ = 0, size_ = 0;
};

/// Consecutive scans taken at one commanded pose.
struct Stop {
  Pose2 commanded;  ///< VIEWPOINT of the stop's first scan
  ScanRange scans;  ///< indices into Sequence::scans, in file order
};

/// The scan headers of a sequence, stored compactly. File names: when they all read
/// PREFIX + a number zero-padded to one width + `.pcd` (scan_000000.pcd, ...), as the prefix, the
/// width and runs of consecutive numbers; otherwise back to back in one buffer. Viewpoint, point
/// count and flags: as runs of scans with equal values (a stop's scans usually share them). A
/// numbered sequence thus costs about 50 bytes per stop instead of 57 bytes per scan (5.5 MB at
/// 100,000 scans). Elements are ScanHeader values made on access; every path shares one directory.
class ScanList {
 public:
  class iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = ScanHeader;
    using difference_type = std::ptrdiff_t;
    using pointer = const ScanHeader*;
    using reference = ScanHeader;
    iterator() = default;
    iterator(const ScanList* list, std::size_t i) : list_(list), i_(i) {}
    ScanHeader operator*() const { return (*list_)[i_]; }
    iterator& operator++() {
      ++i_;
      return *this;
    }
    iterator operator++(int) {
      iterator t = *this;
      ++i_;
      return t;
    }
    bool operator==(const iterator& o) const { return i_ == o.i_; }
    bool operator!=(const iterator& o) const { return i_ != o.i_; }

   private:
    const ScanList* list_ = nullptr;
    std::size_t i_ = 0;
  };
  std::size_t size() const { return size_; }  ///< number of scans (names given)
  bool empty() const { return size_ == 0; }   ///< no scan
  /// Header of scan i (i < size(); throws std::logic_error when its header is not set yet).
  ScanHeader operator[](std::size_t i) const;
  ScanHeader at(std::size_t i) const;         ///< throws std::out_of_range
  std::string path(std::size_t i) const;      ///< the path of scan i (throws std::out_of_range)
  ScanHeader front() const { return at(0); }  ///< header of the first scan
  ScanHeader back() const { return at(size() - 1); }       ///< header of the last scan
  iterator begin() const { return iterator(this, 0); }     ///< first scan
  iterator end() const { return iterator(this, size()); }  ///< past the last scan
  ScanList() = default;
  /// Files `names` in the directory `dir` (with its trailing separator), in this order. The
  /// headers are then set (setHeader), a header can be read once set; the names can be dropped.
  ScanList(std::string dir, const std::vector<std::string>& names);
  /// Files `dir` + `prefix` + numbers[k] zero-padded to `width` digits + `.pcd`, in the order of
  /// `numbers` (throws std::invalid_argument when a number has more than `width` digits or the
  /// width is 0). Headers as with the other constructor.
  static ScanList numbered(std::string dir, std::string prefix, std::size_t width,
                           const std::vector<std::uint64_t>& numbers);
  /// Header of scan i (its path must be the directory + the name given for i). Headers are set
  /// in index order, each once: i must be the number of headers set so far (else
  /// std::invalid_argument), as they are kept as runs of equal values.
  void setHeader(std::size_t i, const ScanHeader& header);
  /// Appends a header; its path must be in the directory of the first one, and every earlier
  /// header must be set (else std::invalid_argument).
  void push_back(const ScanHeader& header);
  /// Runs of consecutive numbers the names are kept as (0: the names are kept as text).
  std::size_t nameRuns() const { return numbered_ ? name_runs_.size() : 0; }
  /// Runs of scans with equal viewpoint, point count and flags.
  std::size_t headerRuns() const { return header_runs_.size(); }
  /// Frees the spare capacity of the run storage (after the last header is set).
  void shrink_to_fit();

 private:
  /// Scans start, start + 1, ... (up to the next run) are named by first, first + 1, ...
  struct NameRun {
    std::uint64_t start;
    std::uint64_t first;
  };
  /// Scans start, start + 1, ... (up to the next run) share these values.
  struct HeaderRun {
    std::uint64_t start;
    Pose2 viewpoint;
    std::uint64_t points;
    std::uint8_t flags;  // has_intensity 1, has_label 2, binary 4
  };
  void appendName(const std::string& name);
  void addNumber(std::uint64_t number);  // numbered form: the next name
  void namesToText();                    // leaves the numbered form for the names buffer
  void appendHeader(const ScanHeader& header);

  std::string dir_;        // the first path without its file name
  std::size_t size_ = 0;   // names given
  bool numbered_ = false;  // names as prefix_ + number + ".pcd" (name_runs_)
  std::string prefix_;
  std::size_t width_ = 0;
  std::vector<NameRun> name_runs_;
  std::string names_;                    // else: file names, back to back
  std::vector<std::uint64_t> name_end_;  // end of each name in names_
  std::vector<HeaderRun> header_runs_;
  std::size_t headers_ = 0;  // headers set: scans 0 .. headers_ - 1
};

/// Tolerances for "same VIEWPOINT" (docs/FORMAT.md: 1 mm and 0.01 degree).
struct StopTolerance {
  double position_m = 1e-3;  ///< max distance between viewpoints of one stop
  double yaw_rad = 0.01 * 3.14159265358979323846 / 180.0;  ///< max heading difference
};

struct Sequence {
  std::filesystem::path dir;  ///< the sequence directory
  ScanList scans;             ///< one per .pcd file, lexicographic order
  std::vector<Stop> stops;    ///< consecutive scans with the same VIEWPOINT
  SequenceMeta meta;          ///< sequence.json, when present
  /// Stop index of scan i (a binary search over the stops; nothing is kept per scan).
  /// Throws std::out_of_range when i >= scans.size().
  std::size_t stopOf(std::size_t i) const;
};

/// Groups consecutive viewpoints into stops; a scan whose index is in `starts` (sorted) begins
/// a new stop whatever its viewpoint.
std::vector<Stop> groupStops(const std::vector<Pose2>& viewpoints, const StopTolerance& tol = {},
                             const std::vector<std::size_t>& starts = {});

/// Lists and checks a sequence directory (headers and sequence.json only). Throws InputError
/// when the directory is missing, holds no .pcd file, a header is bad, a scan file ends in
/// `.PCD` (any case but `.pcd`), two names carry one scan number (`scan_1.pcd`, `scan_0001.pcd`)
/// or numbers without zero padding would be read out of order (`scan_10.pcd` before
/// `scan_2.pcd`), a scan's point count differs from sequence.json `beams`, or a name in
/// sequence.json `stop_starts` is not a scan of the directory.
Sequence openSequence(const std::filesystem::path& dir, const StopTolerance& tol = {});

/// Fewest and most points in a scan of the sequence (equal when every scan has one beam count).
std::pair<std::size_t, std::size_t> pointCountRange(const Sequence& seq);

/// Reads sequence.json (throws InputError on malformed content).
SequenceMeta readSequenceMeta(const std::filesystem::path& file);
/// Writes sequence.json atomically; absent fields are omitted.
void writeSequenceMeta(const std::filesystem::path& file, const SequenceMeta& meta);
/// sequence.json's content: the items of `meta` that are set.
nlohmann::ordered_json sequenceMetaJson(const SequenceMeta& meta);

/// Name of scan file `index` in a sequence written by lidarcal: scan_000000.pcd, ...
std::string scanFileName(std::size_t index);

}  // namespace lidarcal::io
